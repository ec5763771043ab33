#include "client/progress_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace gdvr::client {

std::string format_duration(double s) {
  if (s < 0) return "--:--";
  int t = int(s + 0.5);
  char buf[32];
  if (t >= 3600) std::snprintf(buf, sizeof buf, "%d:%02d:%02d", t / 3600, t / 60 % 60, t % 60);
  else std::snprintf(buf, sizeof buf, "%d:%02d", t / 60, t % 60);
  return buf;
}

void ProgressView::take_progress(const v1::Progress& p, double now_s, bool live_render) {
  if (p.frames_total() > 0) total_ = p.frames_total();
  final_ = std::max(final_, p.frames_done());
  rendered_ = std::max({rendered_, p.frames_rendered(), final_});
  if (live_render) {
    render_fraction_ = std::max(render_fraction_, p.fraction());
    render_eta_ = p.eta_seconds();
    render_eta_at_ = now_s;
  }
}

void ProgressView::on_event(const v1::JobEvent& ev, double now_s) {
  switch (ev.event_case()) {
    case v1::JobEvent::kStarted:
      total_ = ev.started().frames_total();
      final_ = std::max(final_, ev.started().skipped_frames_size());
      rendered_ = std::max(rendered_, final_);
      break;
    case v1::JobEvent::kFrameRendered:
      take_progress(ev.frame_rendered().progress(), now_s, /* live_render = */ true);
      break;
    case v1::JobEvent::kFrameFinal: {
      const v1::FrameFinal& f = ev.frame_final();
      if (!f.last()) break;  // progress rides on a frame's last chunk
      take_progress(f.progress(), now_s, false);
      if (f.final_unix_us() > 0) {  // 0: made final before a server restart
        if (first_final_us_ == 0) {
          first_final_us_ = f.final_unix_us();
          first_final_count_ = final_;
        }
        last_final_us_ = f.final_unix_us();
        last_final_count_ = final_;
        last_final_at_ = now_s;
      }
      break;
    }
    case v1::JobEvent::kCompleted:
      take_progress(ev.completed().progress(), now_s, false);
      completed_ = true;
      final_ = rendered_ = total_;
      break;
    default:
      break;
  }
}

int ProgressView::rendered_percent() const {
  if (total_ <= 0) return 0;
  double f = std::max(render_fraction_, double(rendered_) / total_);
  int pct = int(std::min(1.0, f) * 100 + 0.5);
  // Rounding must not claim a finished stage while a frame is unrendered.
  return rendered_ < total_ ? std::min(pct, 99) : 100;
}

double ProgressView::eta_seconds(double now_s) const {
  if (completed_ || (total_ > 0 && final_ >= total_)) return 0;
  double eta = -1;
  // Rendering: what the server estimates, less the time since it said so.
  if (render_eta_ >= 0 && rendered_ < total_) eta = std::max(0.0, render_eta_ - (now_s - render_eta_at_));
  // Finishing: the final frames' own rate on the server.
  if (last_final_count_ > first_final_count_ && last_final_us_ > first_final_us_) {
    double per_frame = double(last_final_us_ - first_final_us_) * 1e-6 / (last_final_count_ - first_final_count_);
    double left = per_frame * (total_ - final_) - (now_s - last_final_at_);
    eta = std::max(eta, std::max(0.0, left));
  }
  // A frame is still to come: never "0:00" (the old line said 0:00 with 17
  // frames to go), at least the second that rounds to "0:01".
  if (eta >= 0) eta = std::max(eta, 1.0);
  return eta;
}

std::string ProgressView::line(double now_s, const std::string& note) const {
  const int width = 30;
  int fin = 0, ren = 0;
  if (total_ > 0) {
    fin = std::min(width, final_ * width / total_);
    double r = std::max(double(rendered_) / total_, render_fraction_);
    ren = std::max(fin, int(std::min(1.0, r) * width));
  }
  std::string bar = std::string(size_t(fin), '#') + std::string(size_t(ren - fin), '+') +
                    std::string(size_t(width - ren), '.');
  char buf[256];
  std::snprintf(buf, sizeof buf, "[%s] final %d/%d  rendered %d/%d (%d%%)  ETA %s", bar.c_str(), final_, total_,
                rendered_, total_, rendered_percent(), format_duration(eta_seconds(now_s)).c_str());
  std::string out = buf;
  if (!note.empty()) out += "  " + note;
  return out;
}

}  // namespace gdvr::client
