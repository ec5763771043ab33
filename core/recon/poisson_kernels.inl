// The window solve's inner loops (poisson_kernels.h), compiled once per
// instruction set: poisson_kernels_baseline.cpp, poisson_kernels_avx2.cpp
// (-mavx2) and poisson_kernels_avx512.cpp (AVX-512F/VL/DQ), each defining
// GDVR_POISSON_KERNELS as the name of its table. Everything here lives in an
// anonymous namespace and calls no inline function from elsewhere (not even
// std::min; type traits hold no code): an inline function compiled here with AVX instructions could be
// the copy the linker keeps for the whole program.
#if !defined(GDVR_POISSON_KERNELS) || !defined(GDVR_POISSON_KERNELS_ISA)
#error "define GDVR_POISSON_KERNELS (the table's name) and GDVR_POISSON_KERNELS_ISA before including this file"
#endif

#include <type_traits>

#include "core/recon/poisson_kernels.h"

namespace gdvr {

namespace {

// Term bits of a mask byte (core/recon/term.h's order).
constexpr int kBitPrimal = 0, kBitDx = 1, kBitDy = 2, kBitDt = 3, kBitDxdt = 4, kBitDydt = 5;

inline int min_int(int a, int b) { return a < b ? a : b; }

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
// w·1.0f and w·0.0f are exact, so this gives the same bits as FloatWeights
// filled with the same constants.
struct MaskWeights {
  const uint8_t *m, *m_u, *m_p, *m_pu;  // lines (t, y), (t, y−1), (t−1, y), (t−1, y−1)
  float w[6];
  float wp_dropped;

  template <int kBit>
  float on(const uint8_t* row, int i) const {
    return w[kBit] * float((row[i] >> kBit) & 1);
  }
  float p(int i) const { return (m[i] & 1) ? w[kBitPrimal] : wp_dropped; }
  float dx(int i) const { return on<kBitDx>(m, i); }
  float dy(int i) const { return on<kBitDy>(m, i); }
  float dy_u(int i) const { return on<kBitDy>(m_u, i); }
  float dt(int i) const { return on<kBitDt>(m, i); }
  float dt_p(int i) const { return on<kBitDt>(m_p, i); }
  float dxdt(int i) const { return on<kBitDxdt>(m, i); }
  float dxdt_p(int i) const { return on<kBitDxdt>(m_p, i); }
  float dydt(int i) const { return on<kBitDydt>(m, i); }
  float dydt_u(int i) const { return on<kBitDydt>(m_u, i); }
  float dydt_p(int i) const { return on<kBitDydt>(m_p, i); }
  float dydt_pu(int i) const { return on<kBitDydt>(m_pu, i); }
};

// The same weights where all four mask rows are constant over a span of a
// line (everywhere but at the window's borders and around dropped samples):
// broadcast scalars, so the stencil runs without unpacking bits (2.2x faster
// on 720p; the values are the same, so is the result).
struct ConstWeights {
  float wp, wdx, wdy, wdy_u, wdt, wdt_p, wdxdt, wdxdt_p, wdydt, wdydt_u, wdydt_p, wdydt_pu;

  void set(const MaskWeights& m, int i) {
    wp = m.p(i);
    wdx = m.dx(i);
    wdy = m.dy(i);
    wdy_u = m.dy_u(i);
    wdt = m.dt(i);
    wdt_p = m.dt_p(i);
    wdxdt = m.dxdt(i);
    wdxdt_p = m.dxdt_p(i);
    wdydt = m.dydt(i);
    wdydt_u = m.dydt_u(i);
    wdydt_p = m.dydt_p(i);
    wdydt_pu = m.dydt_pu(i);
  }
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
// span s (columns [s·kStencilSpan, (s+1)·kStencilSpan) of the interior) may
// use ConstWeights.
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
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) c.x[a][b] = r.x[a][b];
    for (int s = 0, i0 = 1; i0 < W - 1; ++s) {
      const int i1 = min_int(W - 1, (s + 1) * kStencilSpan);
      if (uniform[s]) {
        c.w.set(r.w, i0 - 1);
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

float apply_line(const StencilLine& line) {
  if (line.masked) {
    RowCtx<MaskWeights> r;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) r.x[a][b] = line.x[a][b];
    r.w.m = line.mask[0];
    r.w.m_u = line.mask[1];
    r.w.m_p = line.mask[2];
    r.w.m_pu = line.mask[3];
    for (int k = 0; k < 6; ++k) r.w.w[k] = line.term_weight[k];
    r.w.wp_dropped = line.dropped_primal_weight;
    return line.temporal ? apply_row<true>(r, line.uniform_spans, line.width, line.p, line.q)
                         : apply_row<false>(r, line.uniform_spans, line.width, line.p, line.q);
  }
  RowCtx<FloatWeights> r;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) r.x[a][b] = line.x[a][b];
  const float* const* w = line.weight_rows;
  r.w = {w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7], w[8], w[9], w[10], w[11]};
  return line.temporal ? apply_row<true>(r, nullptr, line.width, line.p, line.q)
                       : apply_row<false>(r, nullptr, line.width, line.p, line.q);
}

PcgSums update_residual(float* r, const float* q, const float* M, float step, size_t i0, size_t i1) {
  // kLanes independent partial sums: float sums may not be reassociated,
  // so a single accumulator would keep this hot loop scalar.
  constexpr int kLanes = 8;
  float rr_acc[kLanes] = {}, rz_acc[kLanes] = {};
  size_t i = i0;
  for (; i + kLanes <= i1; i += kLanes)
    for (int j = 0; j < kLanes; ++j) {
      const float ri = r[i + j] - step * q[i + j];
      r[i + j] = ri;
      rr_acc[j] += ri * ri;
      rz_acc[j] += ri * ri * M[i + j];
    }
  for (; i < i1; ++i) {
    const float ri = r[i] - step * q[i];
    r[i] = ri;
    rr_acc[0] += ri * ri;
    rz_acc[0] += ri * ri * M[i];
  }
  PcgSums sums;
  for (int j = 0; j < kLanes; ++j) sums.first += rr_acc[j], sums.second += rz_acc[j];
  return sums;
}

void update_solution(float* x, float* p, const float* r, const float* M, float step, float beta, bool last, size_t i0,
                     size_t i1) {
  if (last) {
    for (size_t i = i0; i != i1; ++i) x[i] += step * p[i];
    return;
  }
  for (size_t i = i0; i != i1; ++i) {
    x[i] += step * p[i];
    p[i] = M[i] * r[i] + beta * p[i];
  }
}

}  // namespace

extern const PoissonKernels GDVR_POISSON_KERNELS;
const PoissonKernels GDVR_POISSON_KERNELS = {GDVR_POISSON_KERNELS_ISA, apply_line, update_residual, update_solution};

}  // namespace gdvr
