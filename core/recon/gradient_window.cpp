#include "core/recon/gradient_window.h"

#include <string>

namespace gdvr {

bool GradientWindow::has_temporal_terms() const {
  for (size_t t = 0; t + 1 < frames.size(); ++t)
    for (Term term : {Term::kDt, Term::kDxdt, Term::kDydt})
      if (frames[t]->has(term)) return true;
  return false;
}

Status GradientWindow::validate() const {
  if (frames.empty()) return invalid_argument("gradient window: no frames");
  for (size_t t = 0; t < frames.size(); ++t) {
    const std::string where = "gradient window frame " + std::to_string(t) + ": ";
    if (!frames[t]) return invalid_argument(where + "null frame");
    GDVR_RETURN_IF_ERROR(frames[t]->validate().with_context(where));
    if (frames[t]->width() != width() || frames[t]->height() != height() || frames[t]->channels() != channels())
      return invalid_argument(where + "shape differs from frame 0");
  }
  return Status::Ok();
}

}  // namespace gdvr
