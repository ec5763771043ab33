#include "core/recon/poisson_operator.h"

#include "core/recon/poisson_kernels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>
#include <type_traits>
#include <utility>

namespace gdvr {

namespace {

constexpr int kChunkPixels = 16384;
// apply() walks blocks of kBlockRows lines through all frames, so the rows of
// frames t ± 1 that the temporal stencil reads are still in cache when they
// become the centre frame (frame-major order streamed p three times from DRAM).
constexpr int kBlockRows = 16;
// Mask mode checks for constant weights per span of kStencilSpan columns
// (poisson_kernels.inl), so one dropped sample only slows its own span.
int span_count(int width) { return (width + kStencilSpan - 1) / kStencilSpan; }

}  // namespace

PoissonSystem::PoissonSystem(Grid grid, bool temporal) : grid_(grid), temporal_(temporal) {
  for (Term t : kAllTerms)
    if (!is_temporal(t) || temporal_) w_[term_index(t)].assign(grid_.size(), 0.0f);
  zero_row_.assign(size_t(grid_.width), 0.0f);
}

PoissonSystem::PoissonSystem(Grid grid, bool temporal, const std::array<float, kTermCount>& term_weights,
                             float dropped_primal_weight, std::vector<uint8_t> valid_bits)
    : grid_(grid),
      temporal_(temporal),
      masked_(true),
      term_w_(term_weights),
      dropped_primal_w_(dropped_primal_weight),
      bits_(std::move(valid_bits)) {
  if (!temporal_)
    for (Term t : kAllTerms)
      if (is_temporal(t)) term_w_[term_index(t)] = 0.0f;
  zero_bits_.assign(size_t(grid_.width), 0);
  zero_row_.assign(size_t(grid_.width), 0.0f);
  // Span s of the interior stencil reads mask columns [s·kStencilSpan − 1, (s+1)·kStencilSpan) ∩ [0, W − 1).
  const int W = grid_.width, spans = span_count(W);
  uniform_spans_.assign(size_t(grid_.rows()) * spans, 0);
  all_uniform_.assign(size_t(spans), 1);
  tbb::parallel_for(0, grid_.rows(), [&](int row) {
    const uint8_t* m = bits_.data() + size_t(row) * W;
    for (int s = 0; s < spans; ++s) {
      const int a = std::max(0, s * kStencilSpan - 1), b = std::min(W - 1, (s + 1) * kStencilSpan);
      uniform_spans_[size_t(row) * spans + s] = std::all_of(m + a, m + std::max(a, b), [&](uint8_t v) { return v == m[a]; });
    }
  });
}

int PoissonSystem::row_grain() const { return std::max(1, kChunkPixels / std::max(1, grid_.width)); }

double PoissonSystem::apply(const float* p, float* q) const {
  const PoissonKernels& kernels = poisson_kernels();
  const Grid g = grid_;
  const size_t W = size_t(g.width);
  const auto row_of = [&](const float* base, int t, int y) -> const float* {
    t = std::clamp(t, 0, g.frames - 1);
    y = std::clamp(y, 0, g.height - 1);
    return base + g.index(0, y, t);
  };
  // Weight rows that lie outside the grid are zero: no such constraint.
  const auto wrow = [&](Term term, int t, int y) -> const float* {
    if (t < 0 || y < 0) return zero_row_.data();
    return weights(term).data() + g.index(0, y, t);
  };
  const auto mrow = [&](int t, int y) -> const uint8_t* {
    if (t < 0 || y < 0) return zero_bits_.data();
    return bits_.data() + g.index(0, y, t);
  };
  // Rows outside the grid are zero, hence uniform.
  const int spans = span_count(g.width);
  const auto uniform_row = [&](int t, int y) -> const uint8_t* {
    if (t < 0 || y < 0) return all_uniform_.data();
    return uniform_spans_.data() + (size_t(t) * g.height + y) * spans;
  };
  // One line (t, y) of q = A p; returns its p·q. `uniform` is per-task scratch.
  const auto line = [&](int t, int y, std::vector<uint8_t>& uniform) -> float {
    const size_t row = size_t(t) * g.height + y;
    StencilLine l;
    for (int dt = -1; dt <= 1; ++dt)
      for (int dy = -1; dy <= 1; ++dy) l.x[dt + 1][dy + 1] = row_of(p, t + dt, y + dy);
    l.p = p + row * W;
    l.q = q + row * W;
    l.width = g.width;
    l.temporal = stencil_temporal();
    l.masked = masked_;
    if (masked_) {
      l.mask[0] = mrow(t, y);
      l.mask[1] = mrow(t, y - 1);
      l.mask[2] = mrow(t - 1, y);
      l.mask[3] = mrow(t - 1, y - 1);
      for (int k = 0; k < kTermCount; ++k) l.term_weight[k] = term_w_[k];
      l.dropped_primal_weight = dropped_primal_w_;
      const uint8_t *u0 = uniform_row(t, y), *u1 = uniform_row(t, y - 1);
      const uint8_t *u2 = uniform_row(t - 1, y), *u3 = uniform_row(t - 1, y - 1);
      for (int s = 0; s < spans; ++s) uniform[size_t(s)] = u0[s] & u1[s] & u2[s] & u3[s];
      l.uniform_spans = uniform.data();
    } else {
      // Order of StencilLine::weight_rows; a spatial system has no temporal rows.
      const float** w = l.weight_rows;
      w[0] = wrow(Term::kPrimal, t, y);
      w[1] = wrow(Term::kDx, t, y);
      w[2] = wrow(Term::kDy, t, y);
      w[3] = wrow(Term::kDy, t, y - 1);
      if (l.temporal) {
        w[4] = wrow(Term::kDt, t, y);
        w[5] = wrow(Term::kDt, t - 1, y);
        w[6] = wrow(Term::kDxdt, t, y);
        w[7] = wrow(Term::kDxdt, t - 1, y);
        w[8] = wrow(Term::kDydt, t, y);
        w[9] = wrow(Term::kDydt, t, y - 1);
        w[10] = wrow(Term::kDydt, t - 1, y);
        w[11] = wrow(Term::kDydt, t - 1, y - 1);
      }
    }
    return kernels.apply_line(l);
  };
  // Mask mode walks blocks of kBlockRows lines through all frames (see
  // kBlockRows). Float weights stream twelve weight rows per line: there the
  // long frame-major runs of the original order are faster (3.0 vs 3.3 ns per
  // pixel measured), so that mode keeps one line per unit.
  const bool blocked = masked_;
  const int units = blocked ? (g.height + kBlockRows - 1) / kBlockRows : g.rows();
  const double stencil = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<int>(0, units, blocked ? 1 : row_grain()), 0.0,
      [&](const tbb::blocked_range<int>& range, double acc) {
        std::vector<uint8_t> uniform;
        if (masked_) uniform.resize(size_t(spans));
        for (int unit = range.begin(); unit != range.end(); ++unit) {
          if (!blocked) {
            acc += line(unit / g.height, unit % g.height, uniform);
            continue;
          }
          for (int t = 0; t < g.frames; ++t)
            for (int y = unit * kBlockRows; y < std::min(g.height, (unit + 1) * kBlockRows); ++y)
              acc += line(t, y, uniform);
        }
        return acc;
      },
      std::plus<double>());
  return follows_motion() ? stencil + apply_temporal_targets_part(p, q) : stencil;
}

void PoissonSystem::follow_temporal_targets(const TemporalTargets* targets) {
  temporal_targets_ = targets && !targets->empty() && temporal_ ? targets : nullptr;
  if (!temporal_targets_) return;
  target_blocks_ = classify_target_blocks(grid_, *temporal_targets_);
  temporal_scratch_.resize(size_t(kTemporalTerms) * grid_.size());
}

std::array<float*, kTemporalTerms> PoissonSystem::temporal_planes() const {
  float* h = temporal_scratch_.data();
  return {h, h + grid_.size(), h + 2 * grid_.size()};
}

double PoissonSystem::apply_temporal_targets_part(const float* p, float* q) const {
  const std::array<float*, kTemporalTerms> h = temporal_planes();
  TemporalWeights w;
  for (Term t : {Term::kDt, Term::kDxdt, Term::kDydt}) {
    const int k = temporal_slot(t);
    if (masked_) {
      w.term_weight[k] = term_w_[term_index(t)];
    } else {
      w.weight[k] = w_[term_index(t)].data();
    }
  }
  if (masked_) w.bits = bits_.data();
  apply_temporal_targets(grid_, *temporal_targets_, target_blocks_, p, w, h.data());
  return temporal_targets_adjoint(grid_, *temporal_targets_, target_blocks_, h.data(), /*absolute=*/false, q, p);
}

template <typename Value>
void PoissonSystem::add_temporal_adjoint(Value&& value, bool absolute, float* out) const {
  const std::array<float*, kTemporalTerms> h = temporal_planes();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid_.size(), kChunkPixels), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      for (Term t : {Term::kDt, Term::kDxdt, Term::kDydt})
        h[size_t(temporal_slot(t))][i] = weight_at(t, i) * value(t, i);
  });
  temporal_targets_adjoint(grid_, *temporal_targets_, target_blocks_, h.data(), absolute, out);
}

// Mask mode: v_c = w_c d_c with constant w_c and d_c = 0 where constraint c
// does not exist, so the loop is branch free and vectorises; neighbours
// outside the grid read a zero row. Same sums in the same order as rhs().
void PoissonSystem::rhs_masked(const std::array<const Field*, kTermCount>& targets, Field* b) const {
  const Grid g = grid_;
  b->resize(g.size());
  const auto& w = term_w_;
  tbb::parallel_for(tbb::blocked_range<int>(0, g.rows(), row_grain()), [&](const tbb::blocked_range<int>& range) {
    for (int row = range.begin(); row != range.end(); ++row) {
      const int t = row / g.height, y = row % g.height;
      const auto d = [&](Term term, int dt, int dy) -> const float* {
        const Field* f = targets[term_index(term)];
        if (!f || t + dt < 0 || y + dy < 0) return zero_row_.data();
        return f->data() + g.index(0, y + dy, t + dt);
      };
      const float *p = d(Term::kPrimal, 0, 0), *dx = d(Term::kDx, 0, 0), *dy = d(Term::kDy, 0, 0);
      const float *dy_u = d(Term::kDy, 0, -1), *dt = d(Term::kDt, 0, 0), *dt_p = d(Term::kDt, -1, 0);
      const float *dxdt = d(Term::kDxdt, 0, 0), *dxdt_p = d(Term::kDxdt, -1, 0);
      const float *dydt = d(Term::kDydt, 0, 0), *dydt_u = d(Term::kDydt, 0, -1);
      const float *dydt_p = d(Term::kDydt, -1, 0), *dydt_pu = d(Term::kDydt, -1, -1);
      const float wp = w[0], wdx = w[1], wdy = w[2], wdt = w[3], wdxdt = w[4], wdydt = w[5];
      float* out = b->data() + g.index(0, y, t);
      // il = x − 1 with ls = 0 at x = 0 (no constraint left of column 0).
      const auto at = [&](auto temporal, int x, int il, float ls) {
        double s = wp * p[x];
        s -= wdx * dx[x];
        s += ls * (wdx * dx[il]);
        s -= wdy * dy[x];
        s += wdy * dy_u[x];
        if constexpr (decltype(temporal)::value) {
          s -= wdt * dt[x];
          s += wdt * dt_p[x];
          s += wdxdt * dxdt[x];
          s -= ls * (wdxdt * dxdt[il]);
          s -= wdxdt * dxdt_p[x];
          s += ls * (wdxdt * dxdt_p[il]);
          s += wdydt * dydt[x];
          s -= wdydt * dydt_u[x];
          s -= wdydt * dydt_p[x];
          s += wdydt * dydt_pu[x];
        }
        out[x] = float(s);
      };
      const auto line = [&](auto temporal) {
        at(temporal, 0, 0, 0.0f);
#pragma GCC ivdep
        for (int x = 1; x < g.width; ++x) at(temporal, x, x - 1, 1.0f);
      };
      if (stencil_temporal()) line(std::true_type{});
      else line(std::false_type{});
    }
  });
}

void PoissonSystem::rhs(const std::array<const Field*, kTermCount>& targets, Field* b) const {
  if (masked_) rhs_masked(targets, b);
  else rhs_stencil(targets, b);
  if (!follows_motion()) return;
  // b += Σ Hᵀ W d over the motion-following temporal terms.
  add_temporal_adjoint(
      [&](Term t, size_t i) {
        const Field* d = targets[term_index(t)];
        return d ? (*d)[i] : 0.0f;
      },
      /*absolute=*/false, b->data());
}

void PoissonSystem::rhs_stencil(const std::array<const Field*, kTermCount>& targets, Field* b) const {
  const Grid g = grid_;
  b->resize(g.size());  // every element is written below
  const size_t sx = 1, sy = size_t(g.width), st = g.frame_size();
  // v_c = w_c d_c; b(q) = Σ_c a_c(q) v_c with a_c(q) the coefficient of x(q) in H_c.
  const auto v = [&](Term term, size_t i) -> float {
    const Field* d = targets[term_index(term)];
    return d ? weight_at(term, i) * (*d)[i] : 0.0f;
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, g.rows(), row_grain()), [&](const tbb::blocked_range<int>& range) {
    for (int row = range.begin(); row != range.end(); ++row) {
      const int t = row / g.height, y = row % g.height;
      for (int x = 0; x < g.width; ++x) {
        const size_t i = g.index(x, y, t);
        double s = v(Term::kPrimal, i);
        s -= v(Term::kDx, i);
        if (x > 0) s += v(Term::kDx, i - sx);
        s -= v(Term::kDy, i);
        if (y > 0) s += v(Term::kDy, i - sy);
        if (stencil_temporal()) {
          s -= v(Term::kDt, i);
          if (t > 0) s += v(Term::kDt, i - st);
          s += v(Term::kDxdt, i);
          if (x > 0) s -= v(Term::kDxdt, i - sx);
          if (t > 0) s -= v(Term::kDxdt, i - st);
          if (x > 0 && t > 0) s += v(Term::kDxdt, i - sx - st);
          s += v(Term::kDydt, i);
          if (y > 0) s -= v(Term::kDydt, i - sy);
          if (t > 0) s -= v(Term::kDydt, i - st);
          if (y > 0 && t > 0) s += v(Term::kDydt, i - sy - st);
        }
        (*b)[i] = float(s);
      }
    }
  });
}

void PoissonSystem::diagonal(Field* d) const {
  const Grid g = grid_;
  d->assign(g.size(), 0.0f);
  const size_t sx = 1, sy = size_t(g.width), st = g.frame_size();
  const auto w = [&](Term term, size_t i) { return weight_at(term, i); };
  tbb::parallel_for(tbb::blocked_range<int>(0, g.rows(), row_grain()), [&](const tbb::blocked_range<int>& range) {
    for (int row = range.begin(); row != range.end(); ++row) {
      const int t = row / g.height, y = row % g.height;
      for (int x = 0; x < g.width; ++x) {
        const size_t i = g.index(x, y, t);
        float s = w(Term::kPrimal, i) + w(Term::kDx, i) + w(Term::kDy, i);
        if (x > 0) s += w(Term::kDx, i - sx);
        if (y > 0) s += w(Term::kDy, i - sy);
        if (stencil_temporal()) {
          s += w(Term::kDt, i) + w(Term::kDxdt, i) + w(Term::kDydt, i);
          if (t > 0) s += w(Term::kDt, i - st) + w(Term::kDxdt, i - st) + w(Term::kDydt, i - st);
          if (x > 0) s += w(Term::kDxdt, i - sx);
          if (x > 0 && t > 0) s += w(Term::kDxdt, i - sx - st);
          if (y > 0) s += w(Term::kDydt, i - sy);
          if (y > 0 && t > 0) s += w(Term::kDydt, i - sy - st);
        }
        (*d)[i] = s;
      }
    }
  });
  if (!follows_motion()) return;
  // Every coefficient of a temporal constraint is ±1: its weight adds to the
  // diagonal at each pixel it touches.
  add_temporal_adjoint([](Term, size_t) { return 1.0f; }, /*absolute=*/true, d->data());
}

void constraint_residuals(const Grid& g, Term term, const float* x, const Field& target,
                          const std::vector<uint8_t>& valid, Field* r, const TemporalTargets* targets) {
  r->assign(g.size(), 0.0f);
  if (valid.empty()) return;
  if (is_temporal(term) && targets && !targets->empty()) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, g.size(), kChunkPixels), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t i = range.begin(); i != range.end(); ++i)
        if (valid[i]) (*r)[i] = temporal_target_difference(g, *targets, term, x, i) - target[i];
    });
    return;
  }
  const size_t sx = 1, sy = size_t(g.width), st = g.frame_size();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, g.size(), kChunkPixels), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) {
      if (!valid[i]) continue;
      float h = 0;
      switch (term) {
        case Term::kPrimal: h = x[i]; break;
        case Term::kDx: h = x[i + sx] - x[i]; break;
        case Term::kDy: h = x[i + sy] - x[i]; break;
        case Term::kDt: h = x[i + st] - x[i]; break;
        case Term::kDxdt: h = (x[i + st + sx] - x[i + st]) - (x[i + sx] - x[i]); break;
        case Term::kDydt: h = (x[i + st + sy] - x[i + st]) - (x[i + sy] - x[i]); break;
      }
      (*r)[i] = h - target[i];
    }
  });
}

}  // namespace gdvr
