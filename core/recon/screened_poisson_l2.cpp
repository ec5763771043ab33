// L2 reconstruction: the screened Poisson problem (Kettunen et al. 2015;
// docs/reconstruction.md),
//   (α² I + Σ Hᵀ H) Ī = α² I_g + Σ Hᵀ I_*,
// solved per channel with Jacobi-preconditioned CG, warm-started from the
// primal as in the G-PT release.
#include <algorithm>
#include <cmath>

#include "core/recon/pcg.h"
#include "core/recon/solver_common.h"

namespace gdvr {

PoissonSystem screened_poisson_system(const ConstraintLayout& layout, const ReconSettings& settings) {
  // Constant per term, so the operator keeps one validity byte per pixel
  // instead of six float arrays.
  const double alpha2 = settings.alpha * settings.alpha * settings.term_weight(Term::kPrimal);
  const double s = std::max(1.0, alpha2);
  std::array<float, kTermCount> w{};
  for (Term t : kAllTerms)
    if (!is_temporal(t) || layout.temporal)
      w[term_index(t)] = float((t == Term::kPrimal ? alpha2 : settings.term_weight(t)) / s);
  PoissonSystem A(layout.grid, layout.temporal, w, w[term_index(Term::kPrimal)] * kDroppedPrimalWeight,
                  pack_valid_bits(layout));
  A.follow_temporal_targets(&layout.targets);
  return A;
}

namespace {

// The same problem with the primal's weight α² scaled per pixel by the square
// of `data_weight` (a denoised data term's trust map), in the operator's
// float-weight mode.
PoissonSystem weighted_screened_poisson_system(const ConstraintLayout& layout, const ReconSettings& settings,
                                               const Field& data_weight) {
  const double alpha2 = settings.alpha * settings.alpha * settings.term_weight(Term::kPrimal);
  float max_dw = 1.0f;
  for (float v : data_weight) max_dw = std::max(max_dw, v);
  const double s = std::max(1.0, alpha2 * double(max_dw) * double(max_dw));
  PoissonSystem A(layout.grid, layout.temporal);
  A.follow_temporal_targets(&layout.targets);
  for (Term t : kAllTerms) {
    if (is_temporal(t) && !layout.temporal) continue;
    const std::vector<uint8_t>& valid = layout.mask(t);
    if (valid.empty()) continue;
    const float w = float((t == Term::kPrimal ? alpha2 : settings.term_weight(t)) / s);
    Field& to = A.weights(t);
    for (size_t i = 0; i < to.size(); ++i) {
      if (t != Term::kPrimal) {
        to[i] = valid[i] ? w : 0.0f;
      } else {
        const float d = data_weight[i] * data_weight[i];
        to[i] = valid[i] ? w * d : w * d * kDroppedPrimalWeight;
      }
    }
  }
  return A;
}

}  // namespace

Status solve_screened_poisson_l2(const GradientWindow& window, const ConstraintLayout& layout,
                                 const ReconSettings& settings, ReconResult* result) {
  const Grid& g = layout.grid;

  const Field data_weight = gather_data_weight(window, layout);
  const PoissonSystem A = data_weight.empty() ? screened_poisson_system(layout, settings)
                                              : weighted_screened_poisson_system(layout, settings, data_weight);
  Field inv_diag;
  A.diagonal(&inv_diag);
  invert_diagonal(&inv_diag);

  // ---- One independent solve per channel ----
  // The buffers are reused across channels (each is grid sized).
  Field b, x;
  std::array<Field, kTermCount> d;
  PcgWorkspace workspace;
  for (int c = 0; c < layout.channels; ++c) {
    std::array<const Field*, kTermCount> targets{};
    for (Term t : kAllTerms)
      if (layout.present(t) && (!is_temporal(t) || layout.temporal)) {
        gather_term(window, layout, t, c, &d[term_index(t)]);
        targets[term_index(t)] = &d[term_index(t)];
      }
    A.rhs(targets, &b);
    x = d[term_index(Term::kPrimal)];  // warm start: the primal (0 where dropped)
    const PcgResult r =
        solve_pcg(A, b, inv_diag, &x, settings.l2_max_iterations, settings.l2_tolerance, &workspace);
    result->stats.cg_iterations += r.iterations;
    result->stats.relative_residual = std::max(result->stats.relative_residual, r.relative_residual);
    scatter_channel(g, x, c, result);
  }
  result->stats.outer_iterations = 1;
  return Status::Ok();
}

}  // namespace gdvr
