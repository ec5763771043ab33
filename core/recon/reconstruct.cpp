#include "core/recon/reconstruct.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include "core/recon/solver_common.h"

namespace gdvr {

std::string ReconStats::to_string() const {
  std::ostringstream s;
  s << "cg_iterations=" << cg_iterations << " outer_iterations=" << outer_iterations
    << " relative_residual=" << relative_residual << " non_finite_outputs=" << non_finite_outputs
    << " seconds=" << seconds << " dropped_non_finite={";
  for (Term t : kAllTerms) s << (t == Term::kPrimal ? "" : ",") << term_name(t) << ":" << non_finite_constraints[term_index(t)];
  s << "} dropped_masked={";
  for (Term t : kAllTerms) s << (t == Term::kPrimal ? "" : ",") << term_name(t) << ":" << masked_constraints[term_index(t)];
  s << "}";
  return s.str();
}

void scatter_channel(const Grid& g, const Field& x, int c, ReconResult* result) {
  for (int t = 0; t < g.frames; ++t) {
    Image& img = result->frames[t];
    const int C = img.channels();
    float* out = img.data().data();
    const float* in = x.data() + size_t(t) * g.frame_size();
    for (size_t p = 0; p < g.frame_size(); ++p) out[p * C + c] = in[p];
  }
}

void invert_diagonal(Field* d) {
  for (float& v : *d) v = v > 0 ? 1.0f / v : 0.0f;
}

namespace {

Status solve_none(const GradientWindow& window, const ConstraintLayout& layout, ReconResult* result) {
  for (int c = 0; c < layout.channels; ++c)
    scatter_channel(layout.grid, gather_term(window, layout, Term::kPrimal, c), c, result);
  return Status::Ok();
}

Expected<ReconResult> reconstruct_counting(const GradientWindow& window, const ReconSettings& settings,
                                           const PixelRect* counted) {
  const auto t0 = std::chrono::steady_clock::now();
  GDVR_RETURN_IF_ERROR(settings.validate());
  GDVR_RETURN_IF_ERROR(window.validate());
  const ConstraintLayout layout = build_constraint_layout(window, counted);

  ReconResult result;
  for (int t = 0; t < window.size(); ++t) result.frames.emplace_back(window.width(), window.height(), window.channels());
  result.stats.non_finite_constraints = layout.non_finite;
  result.stats.masked_constraints = layout.masked;

  switch (settings.method) {
    case ReconMethod::kNone: GDVR_RETURN_IF_ERROR(solve_none(window, layout, &result)); break;
    case ReconMethod::kL2: GDVR_RETURN_IF_ERROR(solve_screened_poisson_l2(window, layout, settings, &result)); break;
    case ReconMethod::kL1: GDVR_RETURN_IF_ERROR(solve_irls_l1(window, layout, settings, &result)); break;
    case ReconMethod::kUniform:
    case ReconMethod::kWeighted: GDVR_RETURN_IF_ERROR(solve_control_variates(window, layout, settings, &result)); break;
  }

  // ---- Last line of defence: the solvers keep every quantity finite, but a
  // NaN in an output frame would poison a whole video encode, so count and
  // replace instead of trusting that invariant blindly.
  for (int t = 0; t < window.size(); ++t) {
    const Image& primal = window.frames[t]->buffer(Term::kPrimal);
    std::vector<float>& out = result.frames[t].data();
    for (size_t i = 0; i < out.size(); ++i)
      if (!std::isfinite(out[i])) {
        ++result.stats.non_finite_outputs;
        out[i] = std::isfinite(primal.data()[i]) ? primal.data()[i] : 0.0f;
      }
  }
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

Expected<ReconResult> reconstruct(const GradientWindow& window, const ReconSettings& settings) {
  return reconstruct_counting(window, settings, nullptr);
}

Expected<ReconResult> reconstruct(const GradientWindow& window, const ReconSettings& settings,
                                  const PixelRect& counted) {
  return reconstruct_counting(window, settings, &counted);
}

Expected<ReconResult> reconstruct_frame(const GradientFrame& frame, const ReconSettings& settings) {
  // A one-frame window drops the temporal terms structurally (they reach
  // frame t+1), so the frame is borrowed, not copied: a no-op deleter.
  GradientWindow window;
  window.frames.emplace_back(&frame, [](const GradientFrame*) {});
  return reconstruct(window, settings);
}

}  // namespace gdvr
