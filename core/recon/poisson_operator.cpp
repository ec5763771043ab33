#include "core/recon/poisson_operator.h"

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
// Mask mode checks for constant weights per span of kSpan columns, so one
// dropped sample only slows its own span.
constexpr int kSpan = 64;
int span_count(int width) { return (width + kSpan - 1) / kSpan; }

// Per-constraint float weights: one row pointer per (term, neighbouring row)
// the stencil touches. `_u` is line y − 1, `_p` frame t − 1.
struct FloatWeights {
  const float *wp, *wdx, *wdy, *wdy_u;
  const float *wdt, *wdt_p;
  const float *wdxdt, *wdxdt_p;
  const float *wdydt, *wdydt_u, *wdydt_p, *wdydt_pu;

  float p(int i) const { return wp[i]; }
  float dx(int i) const { return wdx[i]; }
  float dy(int i) const { return wdy[i]; }
  float dy_u(int i) const { return wdy_u[i]; }
  float dt(int i) const { return wdt[i]; }
  float dt_p(int i) const { return wdt_p[i]; }
  float dxdt(int i) const { return wdxdt[i]; }
  float dxdt_p(int i) const { return wdxdt_p[i]; }
  float dydt(int i) const { return wdydt[i]; }
  float dydt_u(int i) const { return wdydt_u[i]; }
  float dydt_p(int i) const { return wdydt_p[i]; }
  float dydt_pu(int i) const { return wdydt_pu[i]; }
};

// Constant per-term weights on packed validity bits: four mask rows replace
// twelve float weight rows (1–2 streamed bytes per pixel instead of ~36).
// w·1.0f and w·0.0f are exact, so this gives bit-identical results to
// FloatWeights filled with the same constants.
struct MaskWeights {
  const uint8_t *m, *m_u, *m_p, *m_pu;  // lines (t, y), (t, y−1), (t−1, y), (t−1, y−1)
  float w[kTermCount];
  float wp_dropped;

  template <Term kT>
  float on(const uint8_t* row, int i) const {
    return w[term_index(kT)] * float((row[i] >> term_index(kT)) & 1);
  }
  float p(int i) const { return (m[i] & 1) ? w[0] : wp_dropped; }
  float dx(int i) const { return on<Term::kDx>(m, i); }
  float dy(int i) const { return on<Term::kDy>(m, i); }
  float dy_u(int i) const { return on<Term::kDy>(m_u, i); }
  float dt(int i) const { return on<Term::kDt>(m, i); }
  float dt_p(int i) const { return on<Term::kDt>(m_p, i); }
  float dxdt(int i) const { return on<Term::kDxdt>(m, i); }
  float dxdt_p(int i) const { return on<Term::kDxdt>(m_p, i); }
  float dydt(int i) const { return on<Term::kDydt>(m, i); }
  float dydt_u(int i) const { return on<Term::kDydt>(m_u, i); }
  float dydt_p(int i) const { return on<Term::kDydt>(m_p, i); }
  float dydt_pu(int i) const { return on<Term::kDydt>(m_pu, i); }
};

// The same weights where all four mask rows are constant over a span of a
// line (everywhere but at the window's borders and around dropped samples):
// broadcast scalars, so the stencil runs without unpacking bits (2.2x faster
// on 720p; the values are the same, so is the result).
struct ConstWeights {
  float wp, wdx, wdy, wdy_u, wdt, wdt_p, wdxdt, wdxdt_p, wdydt, wdydt_u, wdydt_p, wdydt_pu;

  ConstWeights() = default;
  ConstWeights(const MaskWeights& m, int i)
      : wp(m.p(i)),
        wdx(m.dx(i)),
        wdy(m.dy(i)),
        wdy_u(m.dy_u(i)),
        wdt(m.dt(i)),
        wdt_p(m.dt_p(i)),
        wdxdt(m.dxdt(i)),
        wdxdt_p(m.dxdt_p(i)),
        wdydt(m.dydt(i)),
        wdydt_u(m.dydt_u(i)),
        wdydt_p(m.dydt_p(i)),
        wdydt_pu(m.dydt_pu(i)) {}
  float p(int) const { return wp; }
  float dx(int) const { return wdx; }
  float dy(int) const { return wdy; }
  float dy_u(int) const { return wdy_u; }
  float dt(int) const { return wdt; }
  float dt_p(int) const { return wdt_p; }
  float dxdt(int) const { return wdxdt; }
  float dxdt_p(int) const { return wdxdt_p; }
  float dydt(int) const { return wdydt; }
  float dydt_u(int) const { return wdydt_u; }
  float dydt_p(int) const { return wdydt_p; }
  float dydt_pu(int) const { return wdydt_pu; }
};

// Row pointers for the stencil at (y, t): x[dt + 1][dy + 1] is the row of
// frame t + dt, line y + dy, clamped into the grid. A clamped row only ever
// meets a zero weight, so its values never matter (they are finite).
template <class Weights>
struct RowCtx {
  const float* x[3][3];
  Weights w;
};

// (A x)(q) gathered from every constraint that touches q (coefficient a_c(q)
// of x(q) in H_c): y = w_p x + Σ_c a_c(q) w_c (H_c x). `ls` zeroes the
// constraints left of column 0, `il`/`ir` are the clamped neighbours.
template <bool kTemporal, class Weights>
inline float stencil(const RowCtx<Weights>& r, int i, int il, int ir, float ls) {
  const Weights& w = r.w;
  const float* xc = r.x[1][1];
  const float c = xc[i];
  float y = w.p(i) * c;
  y += w.dx(i) * (c - xc[ir]) + ls * w.dx(il) * (c - xc[il]);
  y += w.dy(i) * (c - r.x[1][2][i]) + w.dy_u(i) * (c - r.x[1][0][i]);
  if constexpr (kTemporal) {
    const float* xn = r.x[2][1];
    const float* xp = r.x[0][1];
    y += w.dt(i) * (c - xn[i]) + w.dt_p(i) * (c - xp[i]);
    // H_dxdt at (j, s) = [x(j+1,s+1) − x(j,s+1)] − [x(j+1,s) − x(j,s)]; a = frame s, b = frame s+1.
    const auto hx = [](const float* a, const float* b, int j, int jr) { return (b[jr] - b[j]) - (a[jr] - a[j]); };
    y += w.dxdt(i) * hx(xc, xn, i, ir) - ls * w.dxdt(il) * hx(xc, xn, il, i) - w.dxdt_p(i) * hx(xp, xc, i, ir) +
         ls * w.dxdt_p(il) * hx(xp, xc, il, i);
    // H_dydt at line y, frame s = [b(y+1) − b(y)] − [a(y+1) − a(y)].
    const auto hy = [i](const float* a, const float* ad, const float* b, const float* bd) {
      return (bd[i] - b[i]) - (ad[i] - a[i]);
    };
    y += w.dydt(i) * hy(xc, r.x[1][2], xn, r.x[2][2]) - w.dydt_u(i) * hy(r.x[1][0], xc, r.x[2][0], xn) -
         w.dydt_p(i) * hy(xp, r.x[0][2], xc, r.x[1][2]) + w.dydt_pu(i) * hy(r.x[0][0], xp, r.x[1][0], xc);
  }
  return y;
}

template <bool kTemporal, class Weights>
void apply_interior(const RowCtx<Weights>& r, int i0, int i1, float* q) {
  // q never aliases the inputs; without this promise GCC gives up on the
  // temporal stencil (more pointers than its runtime alias-check budget) and
  // runs it scalar, 3x slower (measured).
#pragma GCC ivdep
  for (int i = i0; i < i1; ++i) q[i] = stencil<kTemporal>(r, i, i - 1, i + 1, 1.0f);
}

// One line of q = A p; returns its p·q. In mask mode `uniform[s]` says whether
// span s (columns [s·kSpan, (s+1)·kSpan) of the interior) may use ConstWeights.
template <bool kTemporal, class Weights>
float apply_row(const RowCtx<Weights>& r, const uint8_t* uniform, int width, const float* p, float* q) {
  const int W = width;
  if (W == 1) {
    q[0] = stencil<kTemporal>(r, 0, 0, 0, 0.0f);
    return p[0] * q[0];
  }
  q[0] = stencil<kTemporal>(r, 0, 0, 1, 0.0f);
  if constexpr (std::is_same_v<Weights, MaskWeights>) {
    RowCtx<ConstWeights> c;
    std::copy(&r.x[0][0], &r.x[0][0] + 9, &c.x[0][0]);
    for (int s = 0, i0 = 1; i0 < W - 1; ++s) {
      const int i1 = std::min(W - 1, (s + 1) * kSpan);
      if (uniform[s]) {
        c.w = ConstWeights(r.w, i0 - 1);
        apply_interior<kTemporal>(c, i0, i1, q);
      } else {
        apply_interior<kTemporal>(r, i0, i1, q);
      }
      i0 = i1;
    }
  } else {
    apply_interior<kTemporal>(r, 1, W - 1, q);
  }
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
  // Span s of the interior stencil reads mask columns [s·kSpan − 1, (s+1)·kSpan) ∩ [0, W − 1).
  const int W = grid_.width, spans = span_count(W);
  uniform_spans_.assign(size_t(grid_.rows()) * spans, 0);
  all_uniform_.assign(size_t(spans), 1);
  tbb::parallel_for(0, grid_.rows(), [&](int row) {
    const uint8_t* m = bits_.data() + size_t(row) * W;
    for (int s = 0; s < spans; ++s) {
      const int a = std::max(0, s * kSpan - 1), b = std::min(W - 1, (s + 1) * kSpan);
      uniform_spans_[size_t(row) * spans + s] = std::all_of(m + a, m + std::max(a, b), [&](uint8_t v) { return v == m[a]; });
    }
  });
}

int PoissonSystem::row_grain() const { return std::max(1, kChunkPixels / std::max(1, grid_.width)); }

double PoissonSystem::apply(const float* p, float* q) const {
  return masked_ ? apply_impl<MaskWeights>(p, q) : apply_impl<FloatWeights>(p, q);
}

template <class Weights>
double PoissonSystem::apply_impl(const float* p, float* q) const {
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
    RowCtx<Weights> r;
    for (int dt = -1; dt <= 1; ++dt)
      for (int dy = -1; dy <= 1; ++dy) r.x[dt + 1][dy + 1] = row_of(p, t + dt, y + dy);
    if constexpr (std::is_same_v<Weights, MaskWeights>) {
      r.w = {mrow(t, y), mrow(t, y - 1), mrow(t - 1, y), mrow(t - 1, y - 1), {}, dropped_primal_w_};
      for (int k = 0; k < kTermCount; ++k) r.w.w[k] = term_w_[k];
    } else {
      r.w.wp = wrow(Term::kPrimal, t, y);
      r.w.wdx = wrow(Term::kDx, t, y);
      r.w.wdy = wrow(Term::kDy, t, y);
      r.w.wdy_u = wrow(Term::kDy, t, y - 1);
      if (temporal_) {
        r.w.wdt = wrow(Term::kDt, t, y);
        r.w.wdt_p = wrow(Term::kDt, t - 1, y);
        r.w.wdxdt = wrow(Term::kDxdt, t, y);
        r.w.wdxdt_p = wrow(Term::kDxdt, t - 1, y);
        r.w.wdydt = wrow(Term::kDydt, t, y);
        r.w.wdydt_u = wrow(Term::kDydt, t, y - 1);
        r.w.wdydt_p = wrow(Term::kDydt, t - 1, y);
        r.w.wdydt_pu = wrow(Term::kDydt, t - 1, y - 1);
      }
    }
    float* qr = q + row * W;
    const float* pr = p + row * W;
    if constexpr (std::is_same_v<Weights, MaskWeights>) {
      const uint8_t *u0 = uniform_row(t, y), *u1 = uniform_row(t, y - 1);
      const uint8_t *u2 = uniform_row(t - 1, y), *u3 = uniform_row(t - 1, y - 1);
      for (int s = 0; s < spans; ++s) uniform[size_t(s)] = u0[s] & u1[s] & u2[s] & u3[s];
    }
    return temporal_ ? apply_row<true>(r, uniform.data(), g.width, pr, qr)
                     : apply_row<false>(r, uniform.data(), g.width, pr, qr);
  };
  // Mask mode walks blocks of kBlockRows lines through all frames (see
  // kBlockRows). Float weights stream twelve weight rows per line: there the
  // long frame-major runs of the original order are faster (3.0 vs 3.3 ns per
  // pixel measured), so that mode keeps one line per unit.
  const bool blocked = masked_;
  const int units = blocked ? (g.height + kBlockRows - 1) / kBlockRows : g.rows();
  return tbb::parallel_deterministic_reduce(
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
      if (temporal_) line(std::true_type{});
      else line(std::false_type{});
    }
  });
}

void PoissonSystem::rhs(const std::array<const Field*, kTermCount>& targets, Field* b) const {
  if (masked_) return rhs_masked(targets, b);
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
  const auto w = [&](Term term, size_t i) { return weight_at(term, i); };
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
