// Image-space control variates (Rousselle, Jarosz, Novák 2016, §4-5): every
// pixel is re-estimated from its own primal and from each neighbour's current
// value corrected by the connecting gradient,
//   x(p) ← [g(p) + Σ_q (x(q) ∓ d_pq)] / (1 + N)          (uniform)
// and in the weighted variant each of these estimates is weighted by the
// inverse of its variance, var(x(q) ∓ d_pq) = var x(q) + var d_pq, with the
// variance of the new x(p) propagated as 1 / Σ weights (independence assumed).
// The anchor is the primal g(p), not x(p): with x(p) the fixed point would be
// the unscreened Poisson solution and the primal would be forgotten. Uniform
// is therefore the Jacobi iteration of the screened Poisson problem with
// α² = 1. Only the first-order terms (dx, dy, dt) give estimates; a mixed
// gradient would need three neighbours per estimate and is not used here.
#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/recon/solver_common.h"

namespace gdvr {

namespace {

constexpr Term kCvTerms[] = {Term::kDx, Term::kDy, Term::kDt};

}  // namespace

Status solve_control_variates(const GradientWindow& window, const ConstraintLayout& layout,
                              const ReconSettings& settings, ReconResult* result) {
  const Grid& g = layout.grid;
  const bool weighted = settings.method == ReconMethod::kWeighted;
  const float floor_var = float(settings.variance_floor);
  const size_t sx = 1, sy = size_t(g.width), st = g.frame_size();
  const size_t step[kTermCount] = {0, sx, sy, st, 0, 0};

  std::vector<Term> terms;
  for (Term t : kCvTerms)
    if (layout.present(t) && settings.term_weight(t) > 0) terms.push_back(t);
  if (weighted)
    for (Term t : kAllTerms) {
      if (t != Term::kPrimal && std::find(terms.begin(), terms.end(), t) == terms.end()) continue;
      for (int f = 0; f < g.frames; ++f)
        if (window.frames[f]->has(t) && window.frames[f]->variance(t).empty())
          return invalid_argument(std::string("weighted reconstruction: frame ") + std::to_string(f) +
                                  " has no variance for '" + term_name(t) + "'");
    }

  for (int c = 0; c < layout.channels; ++c) {
    std::array<Field, kTermCount> d, var;
    d[0] = gather_term(window, layout, Term::kPrimal, c);
    if (weighted) var[0] = gather_variance(window, layout, Term::kPrimal, c);
    for (Term t : terms) {
      d[term_index(t)] = gather_term(window, layout, t, c);
      if (weighted) var[term_index(t)] = gather_variance(window, layout, t, c);
    }
    const std::vector<uint8_t>& pvalid = layout.mask(Term::kPrimal);
    const float wp_uniform = float(settings.term_weight(Term::kPrimal));

    // Jacobi sweeps (double-buffered, so the result is independent of threads).
    Field x = d[0], x_next(g.size());
    Field vx, vx_next;
    if (weighted) {
      vx.resize(g.size());
      for (size_t i = 0; i < g.size(); ++i) vx[i] = pvalid[i] ? std::max(var[0][i], floor_var) : 1e30f;
      vx_next.resize(g.size());
    }
    for (int it = 0; it < settings.cv_iterations; ++it) {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, g.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
          // ---- own primal ----
          double num = 0, den = 0;
          if (pvalid[i]) {
            const double w = weighted ? settings.term_weight(Term::kPrimal) / std::max(var[0][i], floor_var)
                                      : wp_uniform;
            num += w * d[0][i];
            den += w;
          }
          // ---- neighbours through each gradient: constraint at i reaches i+s
          // (x(i) ≈ x(i+s) − d(i)); the one at i−s reaches back (x(i) ≈ x(i−s) + d(i−s)).
          for (Term t : terms) {
            const int k = term_index(t);
            const std::vector<uint8_t>& valid = layout.mask(t);
            const double tw = settings.term_weight(t);
            const size_t s = step[k];
            const auto add = [&](size_t j, size_t nb, double sign) {
              double w = tw;
              if (weighted) w = tw / (double(vx[nb]) + std::max(var[k][j], floor_var));
              num += w * (x[nb] + sign * d[k][j]);
              den += w;
            };
            if (t == Term::kDt && !layout.targets.empty()) {
              // dt links i to its target in the next frame (temporal_targets.h).
              const TemporalTargets& to = layout.targets;
              if (valid[i]) add(i, size_t(int64_t(i) + int64_t(st) + to.next_offset[i]), -1.0);
              if (const int32_t k = to.prev_source[i]; k >= 0 && valid[size_t(k)]) add(size_t(k), size_t(k), +1.0);
              continue;
            }
            if (valid[i]) add(i, i + s, -1.0);
            if (i >= s && valid[i - s]) add(i - s, i - s, +1.0);
          }
          x_next[i] = den > 0 ? float(num / den) : x[i];
          if (weighted) vx_next[i] = den > 0 ? float(std::min(1.0 / den, 1e30)) : vx[i];
        }
      });
      x.swap(x_next);
      if (weighted) vx.swap(vx_next);
    }
    scatter_channel(g, x, c, result);
  }
  result->stats.outer_iterations = settings.cv_iterations;
  return Status::Ok();
}

}  // namespace gdvr
