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

// Columns [c0, c1) whose landing pixels all have offset o (the caller checked
// that every read is inside the grid; a pixel without a target reads the
// shared offset's, under weight 0): forward_scattered's arithmetic on
// contiguous reads, so it vectorises. Everything the loop reads is a local
// (a read through `l` could alias the stores and keep it scalar).
template <bool kMasked>
void forward_block(const TemporalForwardLine& l, int c0, int c1, int32_t o) {
  const int64_t W = l.width;
  const float* __restrict own = l.x + l.begin;
  const float* __restrict own_below = own + W;
  const float* __restrict target = l.x + (l.begin + l.frame_size + o);
  const float* __restrict target_below = target + W;
  const uint8_t* __restrict bits = l.bits;
  const float* __restrict w0 = l.weight[0];
  const float* __restrict w1 = l.weight[1];
  const float* __restrict w2 = l.weight[2];
  const float tw0 = l.term_weight[0], tw1 = l.term_weight[1], tw2 = l.term_weight[2];
  float* __restrict h0 = l.h[0];
  float* __restrict h1 = l.h[1];
  float* __restrict h2 = l.h[2];
  // As in apply_interior: without the promise GCC needs more runtime alias
  // checks than it allows and keeps the loop scalar.
#pragma GCC ivdep
  for (int c = c0; c < c1; ++c) {
    float a0, a1, a2;
    if constexpr (kMasked) {
      a0 = tw0 * float((bits[c] >> kBitDt) & 1);
      a1 = tw1 * float((bits[c] >> kBitDxdt) & 1);
      a2 = tw2 * float((bits[c] >> kBitDydt) & 1);
    } else {
      a0 = w0[c], a1 = w1[c], a2 = w2[c];
    }
    const float xi = own[c], xj = target[c];
    h0[c] = a0 * (xj - xi);
    h1[c] = a1 * ((target[c + 1] - xj) - (own[c + 1] - xi));
    h2[c] = a2 * ((target_below[c] - xj) - (own_below[c] - xi));
  }
}

// Columns [c0, c1) whose targets are scattered, each read where it lies, as
// one loop that AVX2 and AVX-512 run with gathers. Where a constraint does
// not exist its weight is 0 (PoissonSystem's contract), so a pixel without a
// target may read itself (j = n), and the target's right and lower
// neighbours are clamped into the grid.
template <bool kMasked>
void forward_scattered(const TemporalForwardLine& l, int c0, int c1) {
  // 32-bit indices (the map's own type): the gathers GCC emits take those.
  const int32_t W = l.width, n0 = int32_t(l.begin), fs = int32_t(l.frame_size), last = int32_t(l.last);
  const float* __restrict x = l.x;
  const int32_t* __restrict offset = l.next_offset;
  const uint8_t* __restrict bits = l.bits;
  const float* __restrict w0 = l.weight[0];
  const float* __restrict w1 = l.weight[1];
  const float* __restrict w2 = l.weight[2];
  const float tw0 = l.term_weight[0], tw1 = l.term_weight[1], tw2 = l.term_weight[2];
  float* __restrict h0 = l.h[0];
  float* __restrict h1 = l.h[1];
  float* __restrict h2 = l.h[2];
#pragma GCC ivdep
  for (int c = c0; c < c1; ++c) {
    float a0, a1, a2;
    if constexpr (kMasked) {
      a0 = tw0 * float((bits[c] >> kBitDt) & 1);
      a1 = tw1 * float((bits[c] >> kBitDxdt) & 1);
      a2 = tw2 * float((bits[c] >> kBitDydt) & 1);
    } else {
      a0 = w0[c], a1 = w1[c], a2 = w2[c];
    }
    const int32_t o = offset[c];
    const int32_t n = n0 + c;
    const int32_t j = o != kNoTemporalTarget ? n + fs + o : n;
    const int32_t jx = j + 1 < last ? j + 1 : last, jy = j + W < last ? j + W : last;
    const float xi = x[n], xj = x[j];
    h0[c] = a0 * (xj - xi);
    h1[c] = a1 * ((x[jx] - xj) - (x[n + 1] - xi));
    h2[c] = a2 * ((x[jy] - xj) - (x[n + W] - xi));
  }
}

template <bool kMasked>
void forward_line(const TemporalForwardLine& l) {
  forward_scattered<kMasked>(l, 0, 1);  // column 0 (no block starts there)
  for (int b = 0, c0 = 1; c0 < l.width;) {
    // A run of blocks with one offset is one loop (a block is short for a
    // vector loop's entry and exit).
    const int32_t o = l.block_offset[b];
    int end = b + 1;
    while (o != kScatteredBlock && 1 + end * kTargetBlock < l.width && l.block_offset[end] == o) ++end;
    const int c1 = min_int(l.width, 1 + end * kTargetBlock);
    if (o != kScatteredBlock)
      forward_block<kMasked>(l, c0, c1, o);
    else
      forward_scattered<kMasked>(l, c0, c1);
    b = end;
    c0 = c1;
  }
}

void temporal_forward_line(const TemporalForwardLine& line) {
  if (line.masked)
    forward_line<true>(line);
  else
    forward_line<false>(line);
}

// (Hᵀ h)(n) at column c, reading each source wherever it lies. As a source,
// x_t(n) has coefficient −1 in its dt, +1 in its dxdt and dydt, and −1 in
// the dxdt (dydt) of its left (upper) neighbour; as the target of source
// k = prev_source[n]: +1 in dt, −1 in dxdt and dydt, and +1 as the right
// (lower) neighbour of the target of the source landing left of (above) it.
inline float adjoint_pixel(const TemporalAdjointLine& l, int c) {
  const int64_t W = l.width, n = l.begin + c;
  const float *h0 = l.h[0], *h1 = l.h[1], *h2 = l.h[2];
  const float m = l.minus;
  const float left = c > 0 ? h1[n - 1] : 0.0f, above = l.up ? h2[n - W] : 0.0f;
  float s = m * h0[n] + h1[n] + h2[n] + m * (left + above);
  const int32_t k = l.prev_source[n];
  const int32_t kl = c > 0 ? l.prev_source[n - 1] : -1, ku = l.up ? l.prev_source[n - W] : -1;
  const float s0 = k >= 0 ? h0[k] : 0.0f, s1 = k >= 0 ? h1[k] : 0.0f, s2 = k >= 0 ? h2[k] : 0.0f;
  const float sl = kl >= 0 ? h1[kl] : 0.0f, sa = ku >= 0 ? h2[ku] : 0.0f;
  return s + (s0 + m * (s1 + s2) + sl + sa);
}

// Columns [c0, c1), c0 ≥ 1, whose sources (own, left and upper neighbours')
// all lie at m − d (the caller checked that every read is inside the grid):
// adjoint_pixel's arithmetic on contiguous reads (a missing source adds ±0
// here, +0 there).
template <bool kUp>
void adjoint_block(const TemporalAdjointLine& l, int c0, int c1, int32_t d, float* __restrict v) {
  const int64_t W = l.width, n0 = l.begin;
  const float* __restrict h0 = l.h[0];
  const float* __restrict h1 = l.h[1];
  const float* __restrict h2 = l.h[2];
  const int32_t* __restrict prev = l.prev_source;
  const float m = l.minus;
  for (int c = c0; c < c1; ++c) {
    const int64_t n = n0 + c;
    const float above = kUp ? h2[n - W] : 0.0f;
    const float s = m * h0[n] + h1[n] + h2[n] + m * (h1[n - 1] + above);
    // A factor 0 or 1, not a branch: GCC keeps a select of loads scalar.
    const float has = float(prev[n] >= 0), has_left = float(prev[n - 1] >= 0);
    const float s0 = has * h0[n - d], s1 = has * h1[n - d], s2 = has * h2[n - d];
    const float sl = has_left * h1[n - 1 - d];
    float sa = 0.0f;
    if constexpr (kUp) sa = float(prev[n - W] >= 0) * h2[n - W - d];
    v[c] = s + (s0 + m * (s1 + s2) + sl + sa);
  }
}

// Columns [c0, c1), c0 ≥ 1, whose sources are scattered: adjoint_block's
// arithmetic with each source read where it lies (a missing one reads pixel
// 0, times 0), as one loop that AVX2 and AVX-512 run with gathers.
template <bool kUp>
void adjoint_scattered(const TemporalAdjointLine& l, int c0, int c1, float* __restrict v) {
  const int32_t W = l.width, n0 = int32_t(l.begin);
  const float* __restrict h0 = l.h[0];
  const float* __restrict h1 = l.h[1];
  const float* __restrict h2 = l.h[2];
  const int32_t* __restrict prev = l.prev_source;
  const float m = l.minus;
#pragma GCC ivdep
  for (int c = c0; c < c1; ++c) {
    const int32_t n = n0 + c;
    const float above = kUp ? h2[n - W] : 0.0f;
    const float s = m * h0[n] + h1[n] + h2[n] + m * (h1[n - 1] + above);
    const int32_t k = prev[n], kl = prev[n - 1];
    // k for a source, else 0 (prev_source is −1 there), without a select that
    // GCC would turn into a masked gather it cannot emulate.
    const int32_t ks = k & ~(k >> 31), kls = kl & ~(kl >> 31);
    const float has = float(k >= 0), has_left = float(kl >= 0);
    const float s0 = has * h0[ks], s1 = has * h1[ks], s2 = has * h2[ks];
    const float sl = has_left * h1[kls];
    float sa = 0.0f;
    if constexpr (kUp) {
      const int32_t ku = prev[n - W];
      sa = float(ku >= 0) * h2[ku & ~(ku >> 31)];
    }
    v[c] = s + (s0 + m * (s1 + s2) + sl + sa);
  }
}

float temporal_adjoint_line(const TemporalAdjointLine& l) {
  const int W = l.width;
  float* v = l.v;
  v[0] = adjoint_pixel(l, 0);
  for (int b = 0, c0 = 1; c0 < W;) {
    const int32_t d = l.block_source[b];
    int end = b + 1;
    while (d != kScatteredBlock && 1 + end * kTargetBlock < W && l.block_source[end] == d) ++end;
    const int c1 = min_int(W, 1 + end * kTargetBlock);
    if (d == kScatteredBlock && l.up)
      adjoint_scattered<true>(l, c0, c1, v);
    else if (d == kScatteredBlock)
      adjoint_scattered<false>(l, c0, c1, v);
    else if (l.up)
      adjoint_block<true>(l, c0, c1, d, v);
    else
      adjoint_block<false>(l, c0, c1, d, v);
    b = end;
    c0 = c1;
  }
  float* out = l.out;
  for (int c = 0; c < W; ++c) out[c] += v[c];
  if (!l.dot_with) return 0.0f;
  // Eight partial sums, as the CG passes keep.
  const float* p = l.dot_with;
  float part[8] = {};
  int c = 0;
  for (; c + 8 <= W; c += 8)
    for (int k = 0; k < 8; ++k) part[k] += p[c + k] * v[c + k];
  for (; c < W; ++c) part[c % 8] += p[c] * v[c];
  return ((part[0] + part[1]) + (part[2] + part[3])) + ((part[4] + part[5]) + (part[6] + part[7]));
}

}  // namespace

extern const PoissonKernels GDVR_POISSON_KERNELS;
const PoissonKernels GDVR_POISSON_KERNELS = {GDVR_POISSON_KERNELS_ISA,    apply_line,           update_residual,
                                             update_solution,             temporal_forward_line,
                                             temporal_adjoint_line};

}  // namespace gdvr
