// L1 reconstruction (Kettunen et al. 2015; docs/reconstruction.md) by iteratively reweighted least
// squares, as in the G-PT release: round k solves the weighted L2 problem with
// per-constraint weights w = β / (|r| + ε_k), ε_k = ε_0 · decay^(k−1), where r
// is the constraint's residual at the previous solution and β the term weight
// (α for the primal). Each round warm-starts CG from the previous solution.
//
// L1 tends to the median of its constraints, and where a few rare paths carry
// the light (a handful of bright samples among black ones at a few spp) the
// median is far below the mean: the result loses energy, a bias the L2 solve
// does not have (its total equals the primal's). With
// ReconSettings::l1_low_frequencies_from_primal the L1 result gets back the low
// frequencies of what it left of the primal, smoothed by the L2 problem's own
// operator: x += argmin_y α²‖y − (I_g − x)‖² + Σ‖H y‖² (every gradient
// target 0, the same masks). It keeps L1's edges and the primal's unbiased
// local mean; docs/reconstruction.md, "L1 and its energy", has the numbers.
//
// A denoised data term (the window carries a trust map) starts the rounds from
// the denoiser's image, and its own shorter schedule applies
// (ReconSettings::l1_denoised_*; docs/reconstruction.md, "L1 from a denoised
// data term").
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
  A.follow_temporal_targets(&layout.targets);
  // Same scaling argument as the L2 solver: divide by max(1, α) so the base
  // weights stay ≤ 1 whatever α is; IRLS weights are then ≤ 1/ε_k.
  const double alpha = settings.alpha * settings.term_weight(Term::kPrimal);
  const double s = std::max(1.0, alpha);
  std::array<float, kTermCount> base{};
  for (Term t : kAllTerms) base[term_index(t)] = float((t == Term::kPrimal ? alpha : settings.term_weight(t)) / s);

  std::vector<Term> active;
  for (Term t : kAllTerms)
    if (layout.present(t) && (!is_temporal(t) || temporal) && base[term_index(t)] > 0) active.push_back(t);

  // The low-frequency correction's operator (the L2 problem's), built once.
  const bool low_frequencies = settings.l1_low_frequencies_from_primal && base[term_index(Term::kPrimal)] > 0;
  PoissonSystem smooth = low_frequencies ? screened_poisson_system(layout, settings) : PoissonSystem(g, temporal);
  Field smooth_inv_diag;
  if (low_frequencies) {
    smooth.diagonal(&smooth_inv_diag);
    invert_diagonal(&smooth_inv_diag);
  }

  // Per-pixel multipliers of α (a denoised data term's trust map); empty: none.
  // The low-frequency correction below keeps the base α: it gives back the
  // data term's low frequencies at the scale the gradients cannot reach.
  const Field data_weight = gather_data_weight(window, layout);

  const bool from_denoised = !data_weight.empty();
  const int rounds = from_denoised ? settings.l1_denoised_outer_iterations : settings.l1_outer_iterations;
  const double epsilon0 = from_denoised ? settings.l1_denoised_epsilon0 : settings.l1_epsilon0;
  const double decay = from_denoised ? settings.l1_denoised_epsilon_decay : settings.l1_epsilon_decay;

  Field b, inv_diag, residual;
  for (int c = 0; c < layout.channels; ++c) {
    std::array<Field, kTermCount> d;
    std::array<const Field*, kTermCount> targets{};
    for (Term t : active) {
      d[term_index(t)] = gather_term(window, layout, t, c);
      targets[term_index(t)] = &d[term_index(t)];
    }
    Field x = d[term_index(Term::kPrimal)];

    for (int k = 1; k <= rounds; ++k) {
      const float eps = float(epsilon0 * std::pow(decay, k - 1));
      // ---- Reweight: w = β / (|r| + ε_k) on valid constraints ----
      double sum = 0;
      int64_t count = 0;
      for (Term t : active) {
        const std::vector<uint8_t>& valid = layout.mask(t);
        constraint_residuals(g, t, x.data(), d[term_index(t)], valid, &residual, &layout.targets);
        Field& w = A.weights(t);
        const float beta = base[term_index(t)];
        const float* scale = t == Term::kPrimal && !data_weight.empty() ? data_weight.data() : nullptr;
        const auto part = tbb::parallel_deterministic_reduce(
            tbb::blocked_range<size_t>(0, w.size(), 16384), std::pair<double, int64_t>{0.0, 0},
            [&](const tbb::blocked_range<size_t>& r, std::pair<double, int64_t> acc) {
              float local = 0;
              for (size_t i = r.begin(); i != r.end(); ++i) {
                if (valid[i]) {
                  w[i] = (scale ? beta * scale[i] : beta) / (std::fabs(residual[i]) + eps);
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
      if (k == rounds)
        result->stats.relative_residual = std::max(result->stats.relative_residual, r.relative_residual);
    }
    if (low_frequencies) {
      const Field& primal = d[term_index(Term::kPrimal)];
      Field left(x.size()), y(x.size(), 0.0f), b2;
      for (size_t i = 0; i < x.size(); ++i) left[i] = primal[i] - x[i];
      std::array<const Field*, kTermCount> only_primal{};
      only_primal[term_index(Term::kPrimal)] = &left;
      smooth.rhs(only_primal, &b2);
      const PcgResult r =
          solve_pcg(smooth, b2, smooth_inv_diag, &y, settings.l2_max_iterations, settings.l2_tolerance);
      result->stats.cg_iterations += r.iterations;
      for (size_t i = 0; i < x.size(); ++i) x[i] += y[i];
    }
    scatter_channel(g, x, c, result);
  }
  result->stats.outer_iterations = rounds;
  return Status::Ok();
}

}  // namespace gdvr
