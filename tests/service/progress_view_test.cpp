// The CLI's progress line (client/progress_view.h) against a recorded event
// stream of a T-GPT job (tests/service/data/tgpt_watch_events.tsv, made by
// record_watch_events.py): final frames trail rendered ones, and rendering
// ends while several of 24 frames are still to come. The line `gdvr submit
// --watch` drew before took its percentage and ETA from rendering and its
// count from final frames, so from that point on it said 100% and ETA 0:00
// with frames still to come (the issue saw "31/48 frames 100%  ETA 0:00").
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "client/progress_view.h"

namespace gdvr::testing {
namespace {

using client::ProgressView;

struct Recorded {
  double t;
  v1::JobEvent event;
};

std::vector<Recorded> load_stream() {
  std::ifstream in(std::string(GDVR_SOURCE_DIR) + "/tests/service/data/tgpt_watch_events.tsv");
  std::vector<Recorded> out;
  std::string line;
  while (std::getline(in, line)) {
    size_t tab = line.find('\t');
    Recorded r;
    r.t = std::stod(line.substr(0, tab));
    auto st = google::protobuf::util::JsonStringToMessage(line.substr(tab + 1), &r.event);
    EXPECT_TRUE(st.ok()) << st.ToString();
    out.push_back(std::move(r));
  }
  return out;
}

int count(const std::string& s, char c) { return int(std::count(s.begin(), s.end(), c)); }

TEST(ProgressViewTest, RecordedTgptStreamShowsBothStagesAndAnHonestEta) {
  const auto stream = load_stream();
  ASSERT_GT(stream.size(), 30u);
  ProgressView view;
  int frames_received = 0, last_percent = 0, last_final = 0;
  bool saw_render_done_with_frames_left = false;
  std::string line_at_render_end;
  for (size_t i = 0; i < stream.size(); ++i) {
    const auto& [t, ev] = stream[i];
    view.on_event(ev, t);
    if (ev.has_frame_final() && ev.frame_final().last()) ++frames_received;
    const std::string line = view.line(t);
    SCOPED_TRACE("event " + std::to_string(i) + " at " + std::to_string(t) + " s: " + line);
    // The final count is the frames that have arrived; rendered is never behind it.
    if (!ev.has_completed()) {
      EXPECT_EQ(view.frames_final(), frames_received);
    }
    EXPECT_LE(view.frames_final(), view.frames_rendered());
    EXPECT_LE(view.frames_rendered(), view.frames_total());
    EXPECT_GE(view.frames_final(), last_final);
    EXPECT_GE(view.rendered_percent(), last_percent);
    last_final = view.frames_final();
    last_percent = view.rendered_percent();
    if (view.frames_rendered() < view.frames_total()) {
      EXPECT_LT(view.rendered_percent(), 100);
    }
    // The bar: one '#' per final share, '+' for rendered but not final.
    EXPECT_EQ(count(line.substr(0, 32), '#'), view.frames_final() * 30 / view.frames_total());
    // ETA: 0 exactly once every frame is final, never before.
    if (view.frames_final() < view.frames_total()) {
      EXPECT_NE(view.eta_seconds(t), 0.0);
      EXPECT_EQ(line.find("ETA 0:00"), std::string::npos);
    } else {
      EXPECT_EQ(view.eta_seconds(t), 0.0);
      EXPECT_NE(line.find("ETA 0:00"), std::string::npos);
    }
    if (view.rendered_percent() == 100 && view.frames_final() < view.frames_total()) {
      if (!saw_render_done_with_frames_left) line_at_render_end = line;
      saw_render_done_with_frames_left = true;
      // Still time to go: the frames not yet final, at the rate they came.
      EXPECT_GT(view.eta_seconds(t), 0.0);
    }
  }
  // The stream is the case the issue describes: rendering done, frames to come.
  EXPECT_TRUE(saw_render_done_with_frames_left);
  EXPECT_NE(line_at_render_end.find("rendered 24/24 (100%)"), std::string::npos) << line_at_render_end;
  EXPECT_EQ(line_at_render_end.find("final 24/24"), std::string::npos) << line_at_render_end;
  EXPECT_NE(line_at_render_end.find('+'), std::string::npos) << line_at_render_end;  // the lag, drawn
  EXPECT_EQ(view.frames_final(), 24);
  EXPECT_EQ(frames_received, 24);
}

TEST(ProgressViewTest, EtaIsUnknownUntilItCanBeEstimated) {
  ProgressView view;
  v1::JobEvent started;
  started.mutable_started()->set_frames_total(10);
  view.on_event(started, 0);
  EXPECT_EQ(view.eta_seconds(0), -1);
  EXPECT_NE(view.line(0).find("ETA --:--"), std::string::npos) << view.line(0);
  EXPECT_NE(view.line(0).find("final 0/10  rendered 0/10 (0%)"), std::string::npos) << view.line(0);
  v1::JobEvent rendered;
  auto* p = rendered.mutable_frame_rendered()->mutable_progress();
  p->set_frames_total(10);
  p->set_fraction(0.25);
  p->set_eta_seconds(30);
  p->set_frames_rendered(2);
  view.on_event(rendered, 5);
  EXPECT_DOUBLE_EQ(view.eta_seconds(5), 30);
  EXPECT_DOUBLE_EQ(view.eta_seconds(15), 20);  // counts down between events
  EXPECT_DOUBLE_EQ(view.eta_seconds(100), 1);  // overdue: never 0 while frames are to come
  EXPECT_EQ(view.rendered_percent(), 25);
}

TEST(ProgressViewTest, FormatDuration) {
  EXPECT_EQ(client::format_duration(-1), "--:--");
  EXPECT_EQ(client::format_duration(0), "0:00");
  EXPECT_EQ(client::format_duration(65), "1:05");
  EXPECT_EQ(client::format_duration(3723), "1:02:03");
}

}  // namespace
}  // namespace gdvr::testing
