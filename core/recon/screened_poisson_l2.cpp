// L2 reconstruction: the screened Poisson problem of REFERENCE.md §5 (p = 2),
//   (α² I + Σ Hᵀ H) Ī = α² I_g + Σ Hᵀ I_*,
// solved per channel with Jacobi-preconditioned CG, warm-started from the
// primal as in the G-PT release.
#include <algorithm>
#include <cmath>

#include "core/recon/pcg.h"
#include "core/recon/solver_common.h"

namespace gdvr {

Status solve_screened_poisson_l2(const GradientWindow& window, const ConstraintLayout& layout,
                                 const ReconSettings& settings, ReconResult* result) {
  const Grid& g = layout.grid;
  PoissonSystem A(g, layout.temporal);

  // ---- Weights, shared by all channels ----
  // Dividing the objective by s = max(1, α²) changes nothing mathematically but
  // keeps every float weight ≤ 1 for huge α (α² = 1e40 would overflow float).
  const double alpha2 = settings.alpha * settings.alpha * settings.term_weight(Term::kPrimal);
  const double s = std::max(1.0, alpha2);
  for (Term t : kAllTerms) {
    if (is_temporal(t) && !layout.temporal) continue;
    Field& w = A.weights(t);
    const std::vector<uint8_t>& valid = layout.mask(t);
    const float wt = float((t == Term::kPrimal ? alpha2 : settings.term_weight(t)) / s);
    if (t == Term::kPrimal) {
      for (size_t i = 0; i < w.size(); ++i) w[i] = valid[i] ? wt : wt * kDroppedPrimalWeight;
    } else if (!valid.empty()) {
      for (size_t i = 0; i < w.size(); ++i) w[i] = valid[i] ? wt : 0.0f;
    }
  }
  Field inv_diag;
  A.diagonal(&inv_diag);
  invert_diagonal(&inv_diag);

  // ---- One independent solve per channel ----
  Field b;
  for (int c = 0; c < layout.channels; ++c) {
    std::array<Field, kTermCount> d;
    std::array<const Field*, kTermCount> targets{};
    for (Term t : kAllTerms)
      if (layout.present(t) && (!is_temporal(t) || layout.temporal)) {
        d[term_index(t)] = gather_term(window, layout, t, c);
        targets[term_index(t)] = &d[term_index(t)];
      }
    A.rhs(targets, &b);
    Field x = d[term_index(Term::kPrimal)];  // warm start: the primal (0 where dropped)
    const PcgResult r = solve_pcg(A, b, inv_diag, &x, settings.l2_max_iterations, settings.l2_tolerance);
    result->stats.cg_iterations += r.iterations;
    result->stats.relative_residual = std::max(result->stats.relative_residual, r.relative_residual);
    scatter_channel(g, x, c, result);
  }
  result->stats.outer_iterations = 1;
  return Status::Ok();
}

}  // namespace gdvr
