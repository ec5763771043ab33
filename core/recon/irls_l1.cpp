// L1 reconstruction (Kettunen et al. 2015; docs/reconstruction.md) by iteratively reweighted least
// squares, as in the G-PT release: round k solves the weighted L2 problem with
// per-constraint weights w = β / (|r| + ε_k), ε_k = ε_0 · decay^(k−1), where r
// is the constraint's residual at the previous solution and β the term weight
// (α for the primal). Each round warm-starts CG from the previous solution.
#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "core/recon/pcg.h"
#include "core/recon/solver_common.h"

namespace gdvr {

Status solve_irls_l1(const GradientWindow& window, const ConstraintLayout& layout, const ReconSettings& settings,
                     ReconResult* result) {
  const Grid& g = layout.grid;
  const bool temporal = layout.temporal;
  PoissonSystem A(g, temporal);
  // Same scaling argument as the L2 solver: divide by max(1, α) so the base
  // weights stay ≤ 1 whatever α is; IRLS weights are then ≤ 1/ε_k.
  const double alpha = settings.alpha * settings.term_weight(Term::kPrimal);
  const double s = std::max(1.0, alpha);
  std::array<float, kTermCount> base{};
  for (Term t : kAllTerms) base[term_index(t)] = float((t == Term::kPrimal ? alpha : settings.term_weight(t)) / s);

  std::vector<Term> active;
  for (Term t : kAllTerms)
    if (layout.present(t) && (!is_temporal(t) || temporal) && base[term_index(t)] > 0) active.push_back(t);

  Field b, inv_diag, residual;
  for (int c = 0; c < layout.channels; ++c) {
    std::array<Field, kTermCount> d;
    std::array<const Field*, kTermCount> targets{};
    for (Term t : active) {
      d[term_index(t)] = gather_term(window, layout, t, c);
      targets[term_index(t)] = &d[term_index(t)];
    }
    Field x = d[term_index(Term::kPrimal)];

    for (int k = 1; k <= settings.l1_outer_iterations; ++k) {
      const float eps = float(settings.l1_epsilon0 * std::pow(settings.l1_epsilon_decay, k - 1));
      // ---- Reweight: w = β / (|r| + ε_k) on valid constraints ----
      double sum = 0;
      int64_t count = 0;
      for (Term t : active) {
        const std::vector<uint8_t>& valid = layout.mask(t);
        constraint_residuals(g, t, x.data(), d[term_index(t)], valid, &residual);
        Field& w = A.weights(t);
        const float beta = base[term_index(t)];
        const auto part = tbb::parallel_deterministic_reduce(
            tbb::blocked_range<size_t>(0, w.size(), 16384), std::pair<double, int64_t>{0.0, 0},
            [&](const tbb::blocked_range<size_t>& r, std::pair<double, int64_t> acc) {
              float local = 0;
              for (size_t i = r.begin(); i != r.end(); ++i) {
                if (valid[i]) {
                  w[i] = beta / (std::fabs(residual[i]) + eps);
                  local += w[i];
                  ++acc.second;
                } else {
                  w[i] = 0.0f;
                }
              }
              acc.first += local;
              return acc;
            },
            [](std::pair<double, int64_t> a, std::pair<double, int64_t> b2) {
              return std::pair<double, int64_t>{a.first + b2.first, a.second + b2.second};
            });
        sum += part.first;
        count += part.second;
      }
      // ---- Renormalise to mean 1 (docs/stability.md): the minimiser is scale
      // invariant, but weights up to 1/ε_20 ≈ 2e7 would cost float precision
      // in the CG dot products.
      const float norm = (count > 0 && sum > 0) ? float(count / sum) : 1.0f;
      for (Term t : active)
        for (float& w : A.weights(t)) w *= norm;
      for (float& w : A.weights(Term::kPrimal)) w = std::max(w, kDroppedPrimalWeight * base[0] * norm / eps);

      A.diagonal(&inv_diag);
      invert_diagonal(&inv_diag);
      A.rhs(targets, &b);
      const PcgResult r = solve_pcg(A, b, inv_diag, &x, settings.l1_inner_iterations, settings.l1_inner_tolerance);
      result->stats.cg_iterations += r.iterations;
      if (k == settings.l1_outer_iterations)
        result->stats.relative_residual = std::max(result->stats.relative_residual, r.relative_residual);
    }
    scatter_channel(g, x, c, result);
  }
  result->stats.outer_iterations = settings.l1_outer_iterations;
  return Status::Ok();
}

}  // namespace gdvr
