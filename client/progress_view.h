// The progress line of `gdvr submit --watch` and `gdvr watch`, computed from
// the job's event stream alone (no clock but the arrival times given), so a
// recorded stream replays to the same lines in a test.
//
// A job has two stages (Progress in render_service.proto): rendering, then
// finishing (for tgpt a window of frames is solved together, so final frames
// trail rendered ones by up to a window). The line shows both:
//
//   [##########++++++..............] final 14/48  rendered 31/48 (65%)  ETA 0:41
//
// '#' final frames, '+' rendered but not yet final. The ETA is to the last
// final frame: the larger of the server's rendering ETA and the final
// frames' own rate; it is 0 exactly when every frame is final, and while a
// frame is still to come it never shows 0:00.
#pragma once

#include <string>

#include "gdvr/v1/render_service.pb.h"

namespace gdvr::client {

class ProgressView {
 public:
  // `now_s`: when the event arrived (seconds, any origin, non-decreasing).
  void on_event(const v1::JobEvent& event, double now_s);

  int frames_total() const { return total_; }
  int frames_final() const { return final_; }
  int frames_rendered() const { return rendered_; }
  // Rendering progress in percent: 100 only once every frame is rendered.
  int rendered_percent() const;
  // Seconds until the last frame is final at `now_s`; -1: not known yet.
  double eta_seconds(double now_s) const;
  // The line at `now_s`, with `note` appended (e.g. "frame 14").
  std::string line(double now_s, const std::string& note = "") const;

 private:
  void take_progress(const v1::Progress& p, double now_s, bool live_render);

  int total_ = 0, final_ = 0, rendered_ = 0;
  double render_fraction_ = 0;
  bool completed_ = false;
  // The server's rendering ETA and when it arrived.
  double render_eta_ = -1, render_eta_at_ = 0;
  // Final frames' rate, from the server's final_unix_us of the first and the
  // latest final frame this view saw (server time, so replayed frames do not
  // count as fast ones), and when the latest arrived (client time).
  int first_final_count_ = 0, last_final_count_ = 0;
  int64_t first_final_us_ = 0, last_final_us_ = 0;
  double last_final_at_ = 0;
};

// "1:05", "1:02:03"; "--:--" for a negative (unknown) duration.
std::string format_duration(double seconds);

}  // namespace gdvr::client
