#include "core/recon/poisson_operator.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>

namespace gdvr {

namespace {

constexpr int kChunkPixels = 16384;

// Row pointers for the stencil at (y, t): x[dt + 1][dy + 1] is the row of
// frame t + dt, line y + dy, clamped into the grid. A clamped row only ever
// meets a zero weight, so its values never matter (they are finite).
struct RowCtx {
  const float* x[3][3];
  const float *wp, *wdx, *wdy, *wdy_u;
  const float *wdt, *wdt_p;
  const float *wdxdt, *wdxdt_p;
  const float *wdydt, *wdydt_u, *wdydt_p, *wdydt_pu;
};

// (A x)(q) gathered from every constraint that touches q (coefficient a_c(q)
// of x(q) in H_c): y = w_p x + Σ_c a_c(q) w_c (H_c x). `ls` zeroes the
// constraints left of column 0, `il`/`ir` are the clamped neighbours.
template <bool kTemporal>
inline float stencil(const RowCtx& r, int i, int il, int ir, float ls) {
  const float* xc = r.x[1][1];
  const float c = xc[i];
  float y = r.wp[i] * c;
  y += r.wdx[i] * (c - xc[ir]) + ls * r.wdx[il] * (c - xc[il]);
  y += r.wdy[i] * (c - r.x[1][2][i]) + r.wdy_u[i] * (c - r.x[1][0][i]);
  if constexpr (kTemporal) {
    const float* xn = r.x[2][1];
    const float* xp = r.x[0][1];
    y += r.wdt[i] * (c - xn[i]) + r.wdt_p[i] * (c - xp[i]);
    // H_dxdt at (j, s) = [x(j+1,s+1) − x(j,s+1)] − [x(j+1,s) − x(j,s)]; a = frame s, b = frame s+1.
    const auto hx = [](const float* a, const float* b, int j, int jr) { return (b[jr] - b[j]) - (a[jr] - a[j]); };
    y += r.wdxdt[i] * hx(xc, xn, i, ir) - ls * r.wdxdt[il] * hx(xc, xn, il, i) - r.wdxdt_p[i] * hx(xp, xc, i, ir) +
         ls * r.wdxdt_p[il] * hx(xp, xc, il, i);
    // H_dydt at line y, frame s = [b(y+1) − b(y)] − [a(y+1) − a(y)].
    const auto hy = [i](const float* a, const float* ad, const float* b, const float* bd) {
      return (bd[i] - b[i]) - (ad[i] - a[i]);
    };
    y += r.wdydt[i] * hy(xc, r.x[1][2], xn, r.x[2][2]) - r.wdydt_u[i] * hy(r.x[1][0], xc, r.x[2][0], xn) -
         r.wdydt_p[i] * hy(xp, r.x[0][2], xc, r.x[1][2]) + r.wdydt_pu[i] * hy(r.x[0][0], xp, r.x[1][0], xc);
  }
  return y;
}

template <bool kTemporal>
float apply_row(const RowCtx& r, int width, const float* p, float* q) {
  const int W = width;
  if (W == 1) {
    q[0] = stencil<kTemporal>(r, 0, 0, 0, 0.0f);
    return p[0] * q[0];
  }
  q[0] = stencil<kTemporal>(r, 0, 0, 1, 0.0f);
  // q never aliases the inputs; without this promise GCC gives up on the
  // temporal stencil (more pointers than its runtime alias-check budget) and
  // runs it scalar, 3x slower (measured).
#pragma GCC ivdep
  for (int i = 1; i < W - 1; ++i) q[i] = stencil<kTemporal>(r, i, i - 1, i + 1, 1.0f);
  q[W - 1] = stencil<kTemporal>(r, W - 1, W - 2, W - 1, 1.0f);
  // Eight partial sums so the reduction vectorises (no float reassociation).
  float acc[8] = {};
  int i = 0;
  for (; i + 8 <= W; i += 8)
    for (int j = 0; j < 8; ++j) acc[j] += p[i + j] * q[i + j];
  for (; i < W; ++i) acc[0] += p[i] * q[i];
  float dot = 0;
  for (float a : acc) dot += a;
  return dot;
}

}  // namespace

PoissonSystem::PoissonSystem(Grid grid, bool temporal) : grid_(grid), temporal_(temporal) {
  for (Term t : kAllTerms)
    if (!is_temporal(t) || temporal_) w_[term_index(t)].assign(grid_.size(), 0.0f);
  zero_row_.assign(size_t(grid_.width), 0.0f);
}

int PoissonSystem::row_grain() const { return std::max(1, kChunkPixels / std::max(1, grid_.width)); }

double PoissonSystem::apply(const float* p, float* q) const {
  const Grid g = grid_;
  const size_t W = size_t(g.width);
  const auto row_of = [&](const float* base, int t, int y) -> const float* {
    t = std::clamp(t, 0, g.frames - 1);
    y = std::clamp(y, 0, g.height - 1);
    return base + g.index(0, y, t);
  };
  // Weight rows that lie outside the grid are zero: no such constraint.
  const auto wrow = [&](const Field& w, int t, int y) -> const float* {
    if (t < 0 || y < 0) return zero_row_.data();
    return w.data() + g.index(0, y, t);
  };
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<int>(0, g.rows(), row_grain()), 0.0,
      [&](const tbb::blocked_range<int>& range, double acc) {
        for (int row = range.begin(); row != range.end(); ++row) {
          const int t = row / g.height, y = row % g.height;
          RowCtx r;
          for (int dt = -1; dt <= 1; ++dt)
            for (int dy = -1; dy <= 1; ++dy) r.x[dt + 1][dy + 1] = row_of(p, t + dt, y + dy);
          r.wp = wrow(weights(Term::kPrimal), t, y);
          r.wdx = wrow(weights(Term::kDx), t, y);
          r.wdy = wrow(weights(Term::kDy), t, y);
          r.wdy_u = wrow(weights(Term::kDy), t, y - 1);
          if (temporal_) {
            r.wdt = wrow(weights(Term::kDt), t, y);
            r.wdt_p = wrow(weights(Term::kDt), t - 1, y);
            r.wdxdt = wrow(weights(Term::kDxdt), t, y);
            r.wdxdt_p = wrow(weights(Term::kDxdt), t - 1, y);
            r.wdydt = wrow(weights(Term::kDydt), t, y);
            r.wdydt_u = wrow(weights(Term::kDydt), t, y - 1);
            r.wdydt_p = wrow(weights(Term::kDydt), t - 1, y);
            r.wdydt_pu = wrow(weights(Term::kDydt), t - 1, y - 1);
            acc += apply_row<true>(r, g.width, p + row * W, q + row * W);
          } else {
            acc += apply_row<false>(r, g.width, p + row * W, q + row * W);
          }
        }
        return acc;
      },
      std::plus<double>());
}

void PoissonSystem::rhs(const std::array<const Field*, kTermCount>& targets, Field* b) const {
  const Grid g = grid_;
  b->assign(g.size(), 0.0f);
  const size_t sx = 1, sy = size_t(g.width), st = g.frame_size();
  // v_c = w_c d_c; b(q) = Σ_c a_c(q) v_c with a_c(q) the coefficient of x(q) in H_c.
  const auto v = [&](Term term, size_t i) -> float {
    const Field* d = targets[term_index(term)];
    return d ? weights(term)[i] * (*d)[i] : 0.0f;
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
        if (temporal_) {
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
  const auto w = [&](Term term, size_t i) { return weights(term)[i]; };
  tbb::parallel_for(tbb::blocked_range<int>(0, g.rows(), row_grain()), [&](const tbb::blocked_range<int>& range) {
    for (int row = range.begin(); row != range.end(); ++row) {
      const int t = row / g.height, y = row % g.height;
      for (int x = 0; x < g.width; ++x) {
        const size_t i = g.index(x, y, t);
        float s = w(Term::kPrimal, i) + w(Term::kDx, i) + w(Term::kDy, i);
        if (x > 0) s += w(Term::kDx, i - sx);
        if (y > 0) s += w(Term::kDy, i - sy);
        if (temporal_) {
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
}

void constraint_residuals(const Grid& g, Term term, const float* x, const Field& target,
                          const std::vector<uint8_t>& valid, Field* r) {
  r->assign(g.size(), 0.0f);
  if (valid.empty()) return;
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
