// The vector batch's vertex on eight paths at once (vector_batch_state.h),
// compiled once per instruction set: vector_vertex_avx2.cpp (-mavx2) and
// vector_vertex_avx512.cpp (AVX-512F/VL/DQ on the same 8-lane vectors:
// masks, and the 64-bit multiply of PCG32 in one instruction), each defining
// GDVR_VERTEX_KERNEL as its entry point's name. vector_batch.cpp runs the
// best one the CPU has. Everything it uses is its own or an intrinsic: see
// vector_batch_state.h for why.
//
// Each step is the scalar code's in the same order, turned into lane masks:
//   FrameScene::interaction (a triangle of a mesh), Frame,
//   sample_emitter -> FrameScene::sample_emitter_direction (triangle area
//   emitters: area_emitter.cpp; sphere area emitters from outside:
//   sphere_point_in_cone, sincos_turns, sphere_cone_pdf; environment maps
//   (environment_emitter.cpp): sample_alias, uv_to_direction, envmap_lookup;
//   others through view.sample_emitter),
//   connect_emitter -> diffuse_eval_pdf, rough_conductor_eval_pdf or
//   plastic_eval_pdf (two-sided: mirror_to_front), mis_power, shadow_ray,
//   draw_bsdf_numbers, sample_bsdf_drawn -> diffuse_sample,
//   square_to_cosine_hemisphere, rough_conductor_sample (Beckmann visible
//   normals: BeckmannSlopeInversion, erfinv, with core/math/elementary.h's
//   functions) or plastic_sample (fresnel_dielectric, its Dirac lobe
//   included), bsdf.cpp's accept_sample, spawn_ray,
//   russian_roulette_survival.
// A second entry point, GDVR_ENVIRONMENT_KERNEL, is add_emission for rays
// that left the scene, where the environment is a map (environment_along).
// No multiply-add is fused (-ffp-contract=off for the whole build), so the
// vector and scalar forms round alike; VectorBatchTest checks every kernel
// against the scalar batch bit for bit.
#if !defined(GDVR_VERTEX_KERNEL) || !defined(GDVR_ENVIRONMENT_KERNEL)
#error "define GDVR_VERTEX_KERNEL and GDVR_ENVIRONMENT_KERNEL (the entry points' names) before including this file"
#endif

#include <immintrin.h>

// The generators' 64-bit words take 512-bit vectors, which GCC warns change
// the calling convention without AVX-512; they never cross a call (every
// function here is inline in this file).
#pragma GCC diagnostic ignored "-Wpsabi"

#include <cstdint>
#include <cstring>

#include "core/math/distribution.h"
#include "core/math/elementary.h"  // coefficients only: the functions are repeated below
#include "core/math/vec.h"
#include "core/render/vector_batch_state.h"
#include "core/render/ray.h"
#include "core/texture/texture.h"

namespace gdvr {
namespace {

constexpr int kLanes = 8;
constexpr float kFloatMax = 3.40282347e+38f;

typedef float vf __attribute__((vector_size(32)));
typedef int32_t vi __attribute__((vector_size(32)));
typedef uint32_t vu __attribute__((vector_size(32)));
typedef uint64_t vu64 __attribute__((vector_size(64)));

inline vf splat(float x) { return vf{} + x; }
inline vf vsqrt(vf x) { return (vf)_mm256_sqrt_ps((__m256)x); }
// std::sqrt(std::max(0.0f, x)), NaN -> 0 as there.
inline vf safe_vsqrt(vf x) { return vsqrt(0.0f < x ? x : splat(0.0f)); }
inline vf vabs(vf x) { return (vf)((vu)x & 0x7fffffffu); }
// std::max(a, b) and std::min(a, b), operand order included.
inline vf vmax(vf a, vf b) { return a < b ? b : a; }
inline vf vmin(vf a, vf b) { return b < a ? b : a; }
inline vf vsel(vi m, vf a, vf b) { return m ? a : b; }
inline vi finite(vf x) { return vabs(x) <= kFloatMax; }
// std::floor.
inline vf vfloor(vf x) { return (vf)_mm256_round_ps((__m256)x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC); }

struct V3 {
  vf x, y, z;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator-(V3 a) { return {-a.x, -a.y, -a.z}; }
inline V3 operator*(V3 a, vf s) { return {a.x * s, a.y * s, a.z * s}; }
inline V3 operator*(V3 a, V3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline vf vdot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 vsel3(vi m, V3 a, V3 b) { return {vsel(m, a.x, b.x), vsel(m, a.y, b.y), vsel(m, a.z, b.z)}; }
inline vi is_black(V3 c) { return (c.x == 0.0f) & (c.y == 0.0f) & (c.z == 0.0f); }

template <class V>
inline V load(const void* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class V>
inline void store(void* p, V v) {
  std::memcpy(p, &v, sizeof v);
}
inline V3 load3(const float (*a)[kVectorBatch], int k) {
  return {load<vf>(&a[0][k]), load<vf>(&a[1][k]), load<vf>(&a[2][k])};
}
// Stores the lanes in m; the others keep what they held.
inline void store3(float (*a)[kVectorBatch], int k, V3 v, vi m) {
  store(&a[0][k], vsel(m, v.x, load<vf>(&a[0][k])));
  store(&a[1][k], vsel(m, v.y, load<vf>(&a[1][k])));
  store(&a[2][k], vsel(m, v.z, load<vf>(&a[2][k])));
}
inline void store1(float* a, int k, vf v, vi m) { store(a + k, vsel(m, v, load<vf>(a + k))); }
inline void store1(int32_t* a, int k, vi v, vi m) { store(a + k, m ? v : load<vi>(a + k)); }

// Eight 16-float records, field k of all eight in out[k]: two 8 x 8 transposes.
inline void transpose8(__m256 r[8]) {
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44), u1 = _mm256_shuffle_ps(t0, t2, 0xee);
  const __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44), u3 = _mm256_shuffle_ps(t1, t3, 0xee);
  const __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44), u5 = _mm256_shuffle_ps(t4, t6, 0xee);
  const __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44), u7 = _mm256_shuffle_ps(t5, t7, 0xee);
  r[0] = _mm256_permute2f128_ps(u0, u4, 0x20), r[1] = _mm256_permute2f128_ps(u1, u5, 0x20);
  r[2] = _mm256_permute2f128_ps(u2, u6, 0x20), r[3] = _mm256_permute2f128_ps(u3, u7, 0x20);
  r[4] = _mm256_permute2f128_ps(u0, u4, 0x31), r[5] = _mm256_permute2f128_ps(u1, u5, 0x31);
  r[6] = _mm256_permute2f128_ps(u2, u6, 0x31), r[7] = _mm256_permute2f128_ps(u3, u7, 0x31);
}
struct RecordLanes {
  vf f[16];
};
// records[index[i]] for the eight lanes (both record types are 16 floats).
template <class Record>
inline RecordLanes load_records(const Record* records, const uint32_t index[kLanes]) {
  static_assert(sizeof(Record) == 16 * sizeof(float));
  __m256 r[16];
  for (int i = 0; i < kLanes; ++i) {
    const float* rec = reinterpret_cast<const float*>(&records[index[i]]);
    r[i] = _mm256_load_ps(rec);
    r[8 + i] = _mm256_load_ps(rec + 8);
  }
  transpose8(r);
  transpose8(r + 8);
  RecordLanes out;
  for (int k = 0; k < 16; ++k) out.f[k] = (vf)r[k];
  return out;
}

// Pcg32 on eight streams.
struct VPcg32 {
  vu64 state, inc;
  // Pcg32::next_float in the lanes of m; the others' generators stay put.
  vf next_float(vi m) {
    const vu64 old = state;
    const vu xorshifted = __builtin_convertvector(((old >> 18u) ^ old) >> 27u, vu);
    const vu rot = __builtin_convertvector(old >> 59u, vu);
    const vu bits = (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
    const vu64 m64 = __builtin_convertvector(m, vu64);  // 0 or all ones (sign-extended)
    state = ((old * 6364136223846793005ULL + inc) & m64) | (old & ~m64);
    return __builtin_convertvector((vi)(bits >> 8u), vf) * 0x1p-24f;
  }
};

// SurfaceInteraction::offset_p.
inline V3 offset_p(V3 p, vf offset_floor, V3 n, V3 d) {
  vf mag = (offset_floor + vmax(vabs(p.x), vmax(vabs(p.y), vabs(p.z)))) * kRayEpsilon;
  mag = vsel(vdot(n, d) < 0.0f, -mag, mag);
  return p + n * mag;
}

// mis_power(a, b): 0 where a^2 is not positive, 1 where it is infinite.
inline vf mis_power(vf pdf_a, vf pdf_b) {
  const vf a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return vsel(a > 0.0f, vsel(finite(a), a / (a + b), splat(1.0f)), splat(0.0f));
}

// square_to_cosine_hemisphere through the concentric disk (sampling.h).
inline V3 cosine_hemisphere(vf ux, vf uy) {
  const vf x = 2.0f * ux - 1.0f, y = 2.0f * uy - 1.0f;
  const vi origin = (x == 0.0f) & (y == 0.0f);
  const vi x_major = vabs(x) > vabs(y);
  const vf r = vsel(x_major, x, y);
  const vf arg = (kPi / 4.0f) * (vsel(x_major, y, x) / vsel(origin, splat(1.0f), r));
  const vf x2 = arg * arg;  // sincos_eighth_turn
  const vf sn = arg * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f)))));
  const vf cs =
      1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f + x2 * (-1.0f / 3628800.0f)))));
  const vf dx = vsel(origin, splat(0.0f), vsel(x_major, r * cs, r * sn));
  const vf dy = vsel(origin, splat(0.0f), vsel(x_major, r * sn, r * cs));
  return {dx, dy, safe_vsqrt(1.0f - dx * dx - dy * dy)};
}

// ---- core/math/elementary.h on eight lanes, operation for operation ----
inline vf bits_f(vu b) { return (vf)b; }
inline vf to_float(vi x) { return __builtin_convertvector(x, vf); }
inline vi to_int(vf x) { return __builtin_convertvector(x, vi); }
// elementary::polynomial (Estrin's scheme), term for term.
template <size_t N>
struct VEstrin {
  static vf eval(const vf (&b)[N], vf power) {
    vf next[(N + 1) / 2];
    for (size_t j = 0; j < N / 2; ++j) next[j] = b[2 * j] + b[2 * j + 1] * power;
    if (N % 2 == 1) next[N / 2] = b[N - 1];
    return VEstrin<(N + 1) / 2>::eval(next, power * power);
  }
};
template <>
struct VEstrin<1> {
  static vf eval(const vf (&b)[1], vf) { return b[0]; }
};
template <size_t N>
inline vf vpolynomial(const float (&c)[N], vf x) {
  vf b[N];
  for (size_t k = 0; k < N; ++k) b[k] = splat(c[N - 1 - k]);
  return VEstrin<N>::eval(b, x);
}
inline vf vcopysign(vf magnitude, vf sign) { return (vf)(((vu)magnitude & 0x7fffffffu) | ((vu)sign & 0x80000000u)); }

// exp_f.
inline vf vexp(vf x) {
  using namespace elementary;
  const vi in_range = (x >= kExpMin) & (x <= kExpMax);
  const vf xr = vsel(in_range, x, splat(0.0f));
  const vf shifted = xr * kLog2e + kRoundMagic;
  const vf n = shifted - kRoundMagic;
  const vi ni = (vi)((vu)shifted - kRoundMagicBits);
  const vf r = (xr - n * kLn2Hi) - n * kLn2Lo;
  const vf p = vpolynomial(kExpPoly, r) * (r * r) + r + 1.0f;
  const vi half = ni >> 1;
  const vf y = p * bits_f((vu)(half + 127) << 23u) * bits_f((vu)(ni - half + 127) << 23u);
  const vf outside = vsel(x > kExpMax, splat(kInfinity), vsel(x < kExpMin, splat(0.0f), x));  // x: NaN
  return vsel(in_range, y, outside);
}

// log_f.
inline vf vlog(vf x0) {
  using namespace elementary;
  const vi subnormal = x0 < kMinNormal;
  const vf x = vsel(subnormal, x0 * 33554432.0f, x0);
  const vf e_shift = vsel(subnormal, splat(-25.0f), splat(0.0f));
  const vu bits = (vu)x;
  vf e = to_float((vi)(bits >> 23u) - 126) + e_shift;
  vf m = bits_f((bits & 0x007fffffu) | 0x3f000000u);
  const vi small = m < kSqrtHalf;
  e = vsel(small, e - 1.0f, e);
  m = vsel(small, m + m - 1.0f, m - 1.0f);
  vf y = vpolynomial(kLogPoly, m) * m * (m * m);
  y = y + e * kLn2Lo;
  y = y - 0.5f * (m * m);
  const vf result = (m + y) + e * kLn2Hi;
  const vf nan = bits_f(vu{} + 0x7fc00000u);
  return vsel(x0 > 0.0f, vsel(x0 == kInfinity, x0, result), vsel(x0 == 0.0f, splat(-kInfinity), nan));
}

// erfc_large (x >= 1; other lanes get values that are thrown away).
inline vf verfc_large(vf x) {
  using namespace elementary;
  const vf e = vexp(-(x * x));
  const vf q = 1.0f / x;
  const vf t = q * q;
  const vf p = vsel(x < 2.0f, vpolynomial(kErfcNearPoly, t), vpolynomial(kErfcFarPoly, t));
  return e * q * p;
}
inline vf verf(vf x) {
  const vf a = vabs(x);
  const vf small = x * vpolynomial(elementary::kErfPoly, x * x);
  return vsel(a > 1.0f, vcopysign(1.0f - verfc_large(vmax(a, splat(1.0f))), x), small);
}
inline vf verfc(vf x) {
  const vf a = vabs(x);
  const vf small = 1.0f - x * vpolynomial(elementary::kErfPoly, x * x);
  const vf y = verfc_large(vmax(a, splat(1.0f)));
  return vsel(a >= 1.0f, vsel(x < 0.0f, 2.0f - y, y), small);
}

// erfinv (microfacet.cpp).
inline vf verfinv(vf x) {
  vf w = -vlog((1.0f - x) * (1.0f + x));
  const vi central = w < 5.0f;
  const vf wc = w - 2.5f;
  vf pc = splat(2.81022636e-08f);
  pc = 3.43273939e-07f + pc * wc;
  pc = -3.5233877e-06f + pc * wc;
  pc = -4.39150654e-06f + pc * wc;
  pc = 0.00021858087f + pc * wc;
  pc = -0.00125372503f + pc * wc;
  pc = -0.00417768164f + pc * wc;
  pc = 0.246640727f + pc * wc;
  pc = 1.50140941f + pc * wc;
  const vf wt = vsqrt(vsel(central, splat(0.0f), w)) - 3.0f;
  vf pt = splat(-0.000200214257f);
  pt = 0.000100950558f + pt * wt;
  pt = 0.00134934322f + pt * wt;
  pt = -0.00367342844f + pt * wt;
  pt = 0.00573950773f + pt * wt;
  pt = -0.0076224613f + pt * wt;
  pt = 0.00943887047f + pt * wt;
  pt = 1.00167406f + pt * wt;
  pt = 2.83297682f + pt * wt;
  return vsel(central, pc, pt) * x;
}

// std::clamp(v, lo, hi).
inline vf vclamp(vf v, float lo, float hi) { return vsel(v < lo, splat(lo), vsel(hi < v, splat(hi), v)); }

// BeckmannSlopeInversion::solve (beckmann_slope.cpp).
inline void beckmann_slope(vf cos_theta_i, vf ux, vf uy, vf* slope_x, vf* slope_y) {
  const vf tan_theta_i = safe_vsqrt(1.0f - cos_theta_i * cos_theta_i) / cos_theta_i;
  const vf cot_theta_i = 1.0f / tan_theta_i;
  const vf maxval = verf(cot_theta_i);
  const vf u_x = vclamp(ux, 1e-6f, 1.0f - 1e-6f);
  const vf u_y = vclamp(uy, 1e-6f, 1.0f - 1e-6f);
  vf x = maxval - (maxval + 1.0f) * verf(vsqrt(-vlog(u_x)));
  const vf target = u_x * (1.0f + maxval + kInvSqrtPi * tan_theta_i * vexp(-(cot_theta_i * cot_theta_i)));
  for (int i = 0; i < 3; ++i) {  // BeckmannSlopeInversion::kNewtonSteps
    const vf slope = verfinv(x);
    const vf value = 1.0f + x + kInvSqrtPi * tan_theta_i * vexp(-(slope * slope)) - target;
    const vf derivative = 1.0f - slope * tan_theta_i;
    x -= value / derivative;
  }
  *slope_x = verfinv(x);
  *slope_y = verfinv(2.0f * u_y - 1.0f);
}

// normalize (vec.h): unchanged where the length is 0.
inline V3 vnormalize(V3 v) {
  const vf l2 = vdot(v, v);
  return vsel3(l2 > 0.0f, v * (1.0f / vsqrt(l2)), v);
}

// sincos_eighth_turn (sincos.h).
inline void vsincos_eighth_turn(vf x, vf* sn, vf* cs) {
  const vf x2 = x * x;
  *sn = x * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f)))));
  *cs = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f + x2 * (-1.0f / 3628800.0f)))));
}

// sincos_turns (sincos.h).
inline void vsincos_turns(vf t, vf* sin_out, vf* cos_out) {
  const vf k4 = 4.0f * t + 0.5f;
  vi k = to_int(k4);
  k += to_float(k) > k4;  // -1 where the truncation rounded up
  vf sn, cs;
  vsincos_eighth_turn((t - to_float(k) * 0.25f) * (2.0f * kPi), &sn, &cs);
  const vi swap = (k & 1) != 0;
  vu sin_bits = (vu)vsel(swap, cs, sn), cos_bits = (vu)vsel(swap, sn, cs);
  sin_bits ^= (vu)(k & 2) << 30u;
  cos_bits ^= (vu)((k + 1) & 2) << 30u;
  *sin_out = (vf)sin_bits;
  *cos_out = (vf)cos_bits;
}

// Doubles, four or eight to a register.
typedef double vd __attribute__((vector_size(64)));
inline vd to_double(vf x) { return __builtin_convertvector(x, vd); }
inline vf to_single(vd x) { return __builtin_convertvector(x, vf); }
inline vd vsqrt_d(vd x) {
#if defined(__AVX512F__)
  return (vd)_mm512_sqrt_pd((__m512d)x);
#else
  vd out;
  const __m256d lo = _mm256_sqrt_pd(_mm256_loadu_pd((const double*)&x));
  const __m256d hi = _mm256_sqrt_pd(_mm256_loadu_pd((const double*)&x + 4));
  _mm256_storeu_pd((double*)&out, lo);
  _mm256_storeu_pd((double*)&out + 4, hi);
  return out;
#endif
}
typedef int64_t vl __attribute__((vector_size(64)));
inline vd vsel_d(vl m, vd a, vd b) { return m ? a : b; }

// sample_alias (alias_table.cpp) on eight lanes, in double as there, lane
// i picking from the n slots at slots[i]: the bin, its pmf and the number
// remapped within it. The slots' fields are read lane by lane and chosen
// between without branches: one lane at a time, with sample_alias's
// data-dependent branch, the picks were a third of this kernel's samples on
// matpreview, and this form rendered it 1.046x faster (prefetching the
// slots on top bought nothing).
struct AliasPicks {
  vu index;
  vf pmf, u;
};
inline AliasPicks alias_picks(const AliasSlotRecord* const slots[kLanes], uint32_t n, vf u) {
  const vd scaled = to_double(u) * double(n);
  vl k = __builtin_convertvector(scaled, vl);  // size_t(scaled): scaled is in [0, n]
  k = k > int64_t(n) - 1 ? vl{} + (int64_t(n) - 1) : k;
  vd frac = scaled - __builtin_convertvector(k, vd);
  frac = frac < 0.0 ? vd{} : (1.0 < frac ? vd{} + 1.0 : frac);  // std::clamp
  alignas(32) float q[kLanes], pmf[kLanes], alias_pmf[kLanes];
  alignas(32) uint32_t alias[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    const AliasSlotRecord& slot = slots[i][k[i]];
    q[i] = slot.q, alias[i] = slot.alias, pmf[i] = slot.pmf, alias_pmf[i] = slot.alias_pmf;
  }
  const vd qd = to_double(load<vf>(q));
  const vl take = frac < qd;
  const vd r_alias = qd < 1.0 ? (frac - qd) / (1.0 - qd) : vd{};
  const vd r = take ? frac / qd : r_alias;
  const double top = double(0x1.fffffep-1f);
  const vi take32 = __builtin_convertvector(take, vi);
  AliasPicks picks;
  picks.index = take32 ? __builtin_convertvector(k, vu) : load<vu>(alias);
  picks.pmf = vsel(take32, load<vf>(pmf), load<vf>(alias_pmf));
  picks.u = to_single(r < 0.0 ? vd{} : (top < r ? vd{} + top : r));
  return picks;
}

// envmap_lookup (frame_scene.cpp) at (u, v) for the lanes in m (zero
// elsewhere): envmap_texels lane by lane, the bilinear weights in vector.
inline V3 envmap_lookup(const EnvmapRecord& env, vi m, vf u, vf v) {
  alignas(32) float fx_l[kLanes], fy_l[kLanes], t[4][3][kLanes];
  const int iw = env.image_width, ih = env.image_height, ch = env.channels;
  for (int i = 0; i < kLanes; ++i) {
    fx_l[i] = fy_l[i] = 0.0f;
    for (int q = 0; q < 4; ++q) t[q][0][i] = t[q][1][i] = t[q][2][i] = 0.0f;
    if (!m[i]) continue;
    const float x = (0.0f < u[i] ? u[i] : 0.0f) * float(iw) + 0.5f, y = (0.0f < v[i] ? v[i] : 0.0f) * float(ih - 1);
    int xb = int(x), y0 = int(y);
    if (iw < xb) xb = iw;
    if (ih - 1 < y0) y0 = ih - 1;
    const float fx = x - float(xb), fy = y - float(y0);
    fx_l[i] = fx < 0.0f ? 0.0f : (1.0f < fx ? 1.0f : fx);
    fy_l[i] = fy < 0.0f ? 0.0f : (1.0f < fy ? 1.0f : fy);
    int x0 = xb - 1, x1 = xb;
    if (x0 < 0) x0 += iw;
    if (x1 >= iw) x1 -= iw;
    const int y1 = y0 + 1 < ih - 1 ? y0 + 1 : ih - 1;
    const int xs[4] = {x0, x1, x0, x1}, ys[4] = {y0, y0, y1, y1};
    for (int q = 0; q < 4; ++q) {
      const float* p = env.texels + (size_t(ys[q]) * size_t(iw) + size_t(xs[q])) * size_t(ch);
      t[q][0][i] = p[0], t[q][1][i] = p[1], t[q][2][i] = p[2];
    }
  }
  const vf fx = load<vf>(fx_l), fy = load<vf>(fy_l);
  auto bilinear = [&](int c) {
    return (load<vf>(t[0][c]) * (1.0f - fx) + load<vf>(t[1][c]) * fx) * (1.0f - fy) +
           (load<vf>(t[2][c]) * (1.0f - fx) + load<vf>(t[3][c]) * fx) * fy;
  };
  return V3{bilinear(0), bilinear(1), bilinear(2)};
}

// sample_envmap_emitter (core/emitter/environment_emitter.cpp) for the lanes
// in m, from (ux, uy): Distribution2D::sample (alias_picks),
// uv_to_direction, Transform::vector, envmap_lookup (envmap_texels lane by
// lane). Returns where a sample was
// made; there d, pdf (emitter selection included) and weight are set.
inline vi sample_envmap(const EnvmapRecord& env, float select_pdf, vi m, vf ux, vf uy, V3* d, vf* pdf,
                        V3* weight) {
  const AliasSlotRecord* slots[kLanes];
  for (int i = 0; i < kLanes; ++i) slots[i] = env.marginal;
  const AliasPicks y = alias_picks(slots, uint32_t(env.height), vsel(m, uy, splat(0.0f)));
  for (int i = 0; i < kLanes; ++i) slots[i] = env.rows + size_t(y.index[i]) * size_t(env.width);
  const AliasPicks x = alias_picks(slots, uint32_t(env.width), vsel(m, ux, splat(0.0f)));
  const vf pdf_uv = y.pmf * x.pmf * float(env.width) * float(env.height);
  const vf u = (__builtin_convertvector(x.index, vf) + x.u) / float(env.width);
  const vf v = (__builtin_convertvector(y.index, vf) + y.u) / float(env.height);
  // uv_to_direction
  vf sin_theta, cos_theta, sin_phi, cos_phi;
  vsincos_turns(0.5f * v, &sin_theta, &cos_theta);
  vsincos_turns(u, &sin_phi, &cos_phi);
  const V3 local{sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta};
  const vi ok = m & (sin_theta > 1e-7f) & (pdf_uv > 0.0f);
  // Transform::vector, in double as there.
  const vd lx = to_double(local.x), ly = to_double(local.y), lz = to_double(local.z);
  const double(*w)[3] = env.to_world;
  *d = vnormalize(V3{to_single(w[0][0] * lx + w[0][1] * ly + w[0][2] * lz),
                     to_single(w[1][0] * lx + w[1][1] * ly + w[1][2] * lz),
                     to_single(w[2][0] * lx + w[2][1] * ly + w[2][2] * lz)});
  *pdf = pdf_uv / (2.0f * kPi * kPi * sin_theta) * select_pdf;
  const V3 texel = envmap_lookup(env, ok, u, v);
  const vf inv_pdf = 1.0f / *pdf;
  *weight = V3{texel.x * env.scale * inv_pdf, texel.y * env.scale * inv_pdf, texel.z * env.scale * inv_pdf};
  return ok;
}

// sphere_point_in_cone (sampling.h): (sin c, cos c), in float where the
// cone is narrow (sin^2 alpha <= 1/16) and in double elsewhere.
inline void sphere_point_in_cone(vf sin2_alpha, vf u, vf* sin_c, vf* cos_c) {
  const vf inv_one_plus_cos_alpha = 1.0f / (1.0f + vsqrt(1.0f - sin2_alpha));
  const vf one_minus_cos = u * (sin2_alpha * inv_one_plus_cos_alpha);
  const vf sin2 = one_minus_cos * (2.0f - one_minus_cos), cos_theta = 1.0f - one_minus_cos;
  const vf x = vmin(splat(1.0f), u * (2.0f - one_minus_cos) * inv_one_plus_cos_alpha);
  const vf one_minus_cos_c =
      vmax(splat(0.0f), (sin2 + x * cos_theta * cos_theta) / (1.0f + cos_theta * vsqrt(1.0f - x)) -
                            x * vsqrt(sin2_alpha));
  *sin_c = vsqrt(one_minus_cos_c * (2.0f - one_minus_cos_c));
  *cos_c = 1.0f - one_minus_cos_c;
  const vi narrow = sin2_alpha <= 1.0f / 16.0f;
  if (_mm256_testc_si256((__m256i)narrow, _mm256_set1_epi32(-1))) return;
  const vd sin2_max = to_double(sin2_alpha), inv_sin_max = 1.0 / vsqrt_d(sin2_max);
  const vd s2 = vsel_d(1.0 < sin2_max, vd{} + 1.0, sin2_max);  // cone_one_minus_cos_from_sin2
  const vd omc = to_double(u) * (s2 / (1.0 + vsqrt_d(1.0 - s2)));
  const vd dsin2 = omc * (2.0 - omc), dcos_theta = 1.0 - omc;
  const vd sin2_over_sin_max = dsin2 * inv_sin_max;
  const vd r = 1.0 - sin2_over_sin_max * inv_sin_max;
  const vd dcos_c = sin2_over_sin_max + dcos_theta * vsqrt_d(vsel_d(0.0 < r, r, vd{}));
  const vd r2 = 1.0 - dcos_c * dcos_c;
  *sin_c = vsel(narrow, *sin_c, to_single(vsqrt_d(vsel_d(0.0 < r2, r2, vd{}))));
  *cos_c = vsel(narrow, *cos_c, to_single(dcos_c));
}

// A rough Beckmann conductor (conductor.cpp, microfacet.cpp) on eight lanes.
struct VConductor {
  vf alpha_u, alpha_v;
  V3 eta, k, specular;

  // MicrofacetDistribution::eval.
  vf d(V3 m) const {
    const vf alpha_uv = alpha_u * alpha_v, cos_theta = m.z, cos_theta_2 = cos_theta * cos_theta;
    const vf mx = m.x / alpha_u, my = m.y / alpha_v;
    const vf result = vexp(-(mx * mx + my * my) / cos_theta_2) / (kPi * alpha_uv * (cos_theta_2 * cos_theta_2));
    return vsel(~(cos_theta_2 <= 0.0f) & (result * cos_theta > 1e-20f), result, splat(0.0f));
  }
  // MicrofacetDistribution::smith_g1 (Beckmann) in two parts: what depends
  // on v alone (g1_of), and the side test against m. A vertex's wo enters
  // both its emitter connection and its sample, so its part is made once.
  vf g1_of(V3 v) const {
    const vf ux = alpha_u * v.x, vy = alpha_v * v.y;
    const vf xy_alpha_2 = ux * ux + vy * vy;
    const vf a = vabs(v.z) / vsqrt(xy_alpha_2);
    const vf lambda = 0.5f * (vexp(-a * a) * kInvSqrtPi / a - verfc(a));
    const vf g = 1.0f / (1.0f + lambda);
    return vsel((xy_alpha_2 == 0.0f) | (a >= 9.0f), splat(1.0f), g);
  }
  static vf smith_g1(V3 v, V3 m, vf g1_v) { return vsel(vdot(v, m) * v.z <= 0.0f, splat(0.0f), g1_v); }
  vf smith_g1(V3 v, V3 m) const { return smith_g1(v, m, g1_of(v)); }
  // fresnel_conductor per channel, times specular_reflectance.
  V3 fresnel(vf cos_theta_i) const {
    const vf c2 = cos_theta_i * cos_theta_i, s2 = 1.0f - c2, s4 = s2 * s2;
    auto channel = [&](vf e, vf kk) {
      const vf temp1 = e * e - kk * kk - s2;
      const vf a2pb2 = safe_vsqrt(temp1 * temp1 + 4.0f * kk * kk * e * e);
      const vf a = safe_vsqrt(0.5f * (a2pb2 + temp1));
      const vf term1 = a2pb2 + c2, term2 = 2.0f * cos_theta_i * a;
      const vf r_s = (term1 - term2) / (term1 + term2);
      const vf term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
      const vf r_p = r_s * (term3 - term4) / (term3 + term4);
      return 0.5f * (r_s + r_p);
    };
    return V3{channel(eta.x, k.x), channel(eta.y, k.y), channel(eta.z, k.z)} * specular;
  }
  // rough_conductor_eval_pdf on the front side: the value (zero where the
  // scalar code returns {}) and the visible-normal pdf.
  // g1_wo: g1_of(wo).
  void eval_pdf(V3 wo, vf g1_wo, V3 wi, V3* value, vf* pdf) const {
    const V3 h = vnormalize(wo + wi);
    const vf dh = d(h);
    const vf g1_o = smith_g1(wo, h, g1_wo);
    const vf g = g1_o * smith_g1(wi, h);
    const V3 f = fresnel(vdot(wo, h));
    const vi valid = ~(wo.z <= 0.0f) & ~(wi.z <= 0.0f) & ~(vdot(wo, h) <= 0.0f) & ~(vdot(wi, h) <= 0.0f) &
                     ~(dh == 0.0f);
    const V3 zero{splat(0.0f), splat(0.0f), splat(0.0f)};
    *value = vsel3(valid, f * (dh * g / (4.0f * wo.z)), zero);
    *pdf = vsel(valid, dh * g1_o / (4.0f * wo.z), splat(0.0f));
  }
  // rough_conductor_sample through Beckmann visible normals, with
  // bsdf_sample's acceptance: where `ok`, the direction, weight and pdf.
  vi sample(V3 wo, vf g1_wo, vf ux, vf uy, V3* wi_out, V3* weight, vf* pdf_out) const {
    const V3 wi_p = vnormalize(V3{alpha_u * wo.x, alpha_v * wo.y, wo.z});  // stretch
    vf sx, sy;
    beckmann_slope(wi_p.z, ux, uy, &sx, &sy);
    // sincos_phi(wi_p) (microfacet.cpp)
    const vf sin_theta_2 = 1.0f - wi_p.z * wi_p.z;
    const vi pole = vabs(sin_theta_2) <= 4.0f * 5.96046448e-8f;
    const vf inv = 1.0f / vsqrt(sin_theta_2);
    const vf sin_phi = vsel(pole, splat(0.0f), vclamp(wi_p.y * inv, -1.0f, 1.0f));
    const vf cos_phi = vsel(pole, splat(1.0f), vclamp(wi_p.x * inv, -1.0f, 1.0f));
    const vf slope_x = (cos_phi * sx - sin_phi * sy) * alpha_u;
    const vf slope_y = (sin_phi * sx + cos_phi * sy) * alpha_v;
    V3 m = vnormalize(V3{-slope_x, -slope_y, splat(1.0f)});
    const vi m_finite = finite(m.x) & finite(m.y) & finite(m.z);
    m = vsel3(m_finite, m, V3{splat(0.0f), splat(0.0f), splat(1.0f)});
    // MicrofacetDistribution::pdf(wo, m) with visible normals.
    const vf dm = d(m);
    const vf pdf_visible = dm * smith_g1(wo, m, g1_wo) * vabs(vdot(wo, m)) / wo.z;
    const vf pdf_m = vsel(m_finite & ~(dm == 0.0f) & ~(wo.z == 0.0f), pdf_visible, splat(0.0f));
    // reflect_on_microfacet
    const V3 wi = m * (2.0f * vdot(wo, m)) - wo;
    const vf wi_dot_m = vdot(wi, m);
    const vf g = smith_g1(wi, m);
    const vf pdf = pdf_m / (4.0f * wi_dot_m);
    *weight = fresnel(vdot(wo, m)) * g;
    *wi_out = wi;
    *pdf_out = pdf;
    vi ok = ~(wo.z <= 0.0f) & (pdf_m > 0.0f) & ~(wi.z <= 0.0f) & (wi_dot_m > 0.0f) & (pdf > 0.0f);
    // accept_sample (bsdf.cpp)
    ok &= finite(weight->x) & finite(weight->y) & finite(weight->z) & finite(pdf) & finite(wi.x) & finite(wi.y) &
          finite(wi.z);
    return ok;
  }
};

// fresnel_dielectric(cos_theta_i, eta).f (fresnel.h); rcp_eta = 1 / eta.
inline vf vfresnel_dielectric(vf cos_theta_i, vf eta, vf rcp_eta) {
  const vi outside = cos_theta_i >= 0.0f;
  const vf eta_it = vsel(outside, eta, rcp_eta), eta_ti = vsel(outside, rcp_eta, eta);
  const vf cos_theta_t_sqr = 1.0f - (1.0f - cos_theta_i * cos_theta_i) * (eta_ti * eta_ti);
  const vf ci = vabs(cos_theta_i);
  const vf ct = safe_vsqrt(cos_theta_t_sqr);
  const vf a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
  const vf a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
  const vf f = 0.5f * (a_s * a_s + a_p * a_p);
  return vsel(eta == 1.0f, splat(0.0f), vsel(ci == 0.0f, splat(1.0f), f));
}

// Smooth plastic (plastic.cpp) on eight lanes, on the front side. `base`:
// the diffuse base (the triangle record's albedo); f_o: the Fresnel
// reflectance of wo, which a vertex's emitter connection and its sample share.
struct VPlastic {
  vf eta, rcp_eta, inv_eta2, specular_weight;
  V3 specular;

  vf fresnel(vf cos_theta) const { return vfresnel_dielectric(cos_theta, eta, rcp_eta); }
  // plastic_eval_pdf: the value (zero where the scalar code returns {}) and the pdf.
  void eval_pdf(V3 base, vf wo_z, vf f_o, vf wi_z, V3* value, vf* pdf) const {
    const vf f_i = fresnel(wi_z);
    const vf cos_pdf = kInvPi * wi_z;
    const vf prob_specular = f_o * specular_weight, prob_diffuse = (1.0f - f_o) * (1.0f - specular_weight);
    const vi valid = ~(wo_z <= 0.0f) & ~(wi_z <= 0.0f);
    const V3 zero{splat(0.0f), splat(0.0f), splat(0.0f)};
    *value = vsel3(valid, base * (cos_pdf * inv_eta2 * (1.0f - f_o) * (1.0f - f_i)), zero);
    *pdf = vsel(valid, cos_pdf * prob_diffuse / (prob_specular + prob_diffuse), splat(0.0f));
  }
  // plastic_sample with bsdf_sample's acceptance, the diffuse lobe's
  // direction (square_to_cosine_hemisphere) given: where `ok`, the
  // direction, weight and pdf; *delta where the Dirac lobe was chosen.
  vi sample(V3 base, V3 wo, vf f_o, vf u_lobe, V3 wi_diffuse, V3* wi_out, V3* weight, vf* pdf_out,
            vi* delta) const {
    vf prob_specular = f_o * specular_weight, prob_diffuse = (1.0f - f_o) * (1.0f - specular_weight);
    prob_specular = prob_specular / (prob_specular + prob_diffuse);
    prob_diffuse = 1.0f - prob_specular;
    const vi specular_lobe = u_lobe < prob_specular;
    const vf pdf_diffuse = prob_diffuse * (kInvPi * wi_diffuse.z);
    const vf f_i = fresnel(wi_diffuse.z);
    const V3 weight_diffuse = base * (inv_eta2 * (1.0f - f_o) * (1.0f - f_i) / prob_diffuse);
    *wi_out = vsel3(specular_lobe, V3{-wo.x, -wo.y, wo.z}, wi_diffuse);  // reflect_local
    *pdf_out = vsel(specular_lobe, prob_specular, pdf_diffuse);
    *weight = vsel3(specular_lobe, specular * (f_o / prob_specular), weight_diffuse);
    *delta = specular_lobe;
    vi ok = ~(wo.z <= 0.0f) & (specular_lobe | (pdf_diffuse > 0.0f));
    // accept_sample (bsdf.cpp)
    ok &= finite(weight->x) & finite(weight->y) & finite(weight->z) & finite(*pdf_out) & (*pdf_out > 0.0f) &
          finite(wi_out->x) & finite(wi_out->y) & finite(wi_out->z);
    return ok;
  }
};

// atan2_turns (arctan.h).
inline vf vatan2_turns(vf y, vf x) {
  const vf sum = x + y;
  const vf ax = vabs(x), ay = vabs(y);
  const vf hi = vmax(ax, ay), lo = vmin(ax, ay);
  const vf a = vsel(hi > 0.0f, lo / hi, splat(0.0f));
  const vf s = a * a;
  vf t = a * (0.15915492177009583f +
              s * (-0.05304967612028122f +
                   s * (0.03178545460104942f +
                        s * (-0.022328631952404976f +
                             s * (0.015824681147933006f +
                                  s * (-0.00953451357781887f +
                                       s * (0.003908644430339336f + s * -0.0007609020103700459f)))))));
  t = vsel(ay > ax, 0.25f - t, t);
  t = vsel((vi)x < 0, 0.5f - t, t);  // signbit(x)
  const vf signed_t = (vf)(((vu)t & 0x7fffffffu) | ((vu)y & 0x80000000u));  // copysign(t, y)
  return vsel(sum != sum, sum, signed_t);
}
// acos_half_turns (arctan.h).
inline vf vacos_half_turns(vf c) {
  c = vclamp(c, -1.0f, 1.0f);
  return 2.0f * vatan2_turns(vsqrt((1.0f - c) * (1.0f + c)), c);
}

// add_emission for lanes whose rays left the scene, with an environment
// map: FrameScene::environment_along (Transform::vector in double,
// direction_to_uv, envmap_lookup, envmap_direction_pdf with
// Distribution2D::pdf) and the MIS-weighted sum, eight lanes of `lanes` at
// a time.
void add_environment_group(const VectorSceneView& scene, VectorBatchState* st, const int32_t* lanes, int n,
                           bool hide_camera_rays) {
  const EnvmapRecord& env = *scene.envmap;
  alignas(32) float dl[3][kLanes], tl[3][kLanes], rl[3][kLanes], il[3][kLanes], prev_pdf[kLanes];
  alignas(32) int32_t prev_delta[kLanes], depth_l[kLanes], active_l[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    const int lane = i < n ? lanes[i] : lanes[0];
    active_l[i] = i < n ? -1 : 0;
    for (int c = 0; c < 3; ++c) {
      dl[c][i] = st->d[c][lane];
      tl[c][i] = st->throughput[c][lane];
      rl[c][i] = st->result[c][lane];
      il[c][i] = st->direct[c][lane];
    }
    prev_pdf[i] = st->prev_pdf[lane];
    prev_delta[i] = st->prev_delta[lane];
    depth_l[i] = st->depth[lane];
  }
  const vi depth = load<vi>(depth_l);
  vi m = load<vi>(active_l);
  if (hide_camera_rays) m &= depth != 0;
  // environment_along
  const vd dx = to_double(load<vf>(dl[0])), dy = to_double(load<vf>(dl[1])), dz = to_double(load<vf>(dl[2]));
  const double(*w)[3] = env.to_local;
  const V3 local = vnormalize(V3{to_single(w[0][0] * dx + w[0][1] * dy + w[0][2] * dz),
                                 to_single(w[1][0] * dx + w[1][1] * dy + w[1][2] * dz),
                                 to_single(w[2][0] * dx + w[2][1] * dy + w[2][2] * dz)});
  const vf u_signed = vatan2_turns(local.x, -local.z);
  const vf u = vsel(u_signed < 0.0f, u_signed + 1.0f, u_signed), v = vacos_half_turns(local.y);
  const V3 texel = envmap_lookup(env, m, u, v);
  const V3 radiance{texel.x * env.scale, texel.y * env.scale, texel.z * env.scale};
  // envmap_direction_pdf: Distribution2D::pdf lane by lane.
  alignas(32) float table_pdf[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    table_pdf[i] = 0.0f;
    if (!m[i]) continue;
    int x = int(u[i] * float(env.width)), y = int(v[i] * float(env.height));
    x = x < 0 ? 0 : (env.width - 1 < x ? env.width - 1 : x);
    y = y < 0 ? 0 : (env.height - 1 < y ? env.height - 1 : y);
    table_pdf[i] = env.marginal[y].pmf * env.rows[size_t(y) * size_t(env.width) + size_t(x)].pmf *
                   float(env.width) * float(env.height);
  }
  const vf xz = local.x * local.x + local.z * local.z;
  const vf sin_theta = vsqrt(vsel(xz < 1e-14f, splat(1e-14f), xz));
  const vf pdf = load<vf>(table_pdf) / (2.0f * kPi * kPi * sin_theta) * scene.select_pdf;
  // add_emission's sum.
  const vi seen = m & ~is_black(radiance);
  const vf weight = vsel(load<vi>(prev_delta) != 0, splat(1.0f), mis_power(load<vf>(prev_pdf), pdf));
  const V3 throughput{load<vf>(tl[0]), load<vf>(tl[1]), load<vf>(tl[2])};
  const V3 contrib = throughput * radiance * weight;
  const V3 result = V3{load<vf>(rl[0]), load<vf>(rl[1]), load<vf>(rl[2])} + contrib;
  const V3 direct = V3{load<vf>(il[0]), load<vf>(il[1]), load<vf>(il[2])} + contrib;
  const vi camera = seen & (depth == 0);
  for (int i = 0; i < n && i < kLanes; ++i) {
    if (!seen[i]) continue;
    const int lane = lanes[i];
    st->result[0][lane] = result.x[i], st->result[1][lane] = result.y[i], st->result[2][lane] = result.z[i];
    if (!camera[i]) continue;
    st->direct[0][lane] = direct.x[i], st->direct[1][lane] = direct.y[i], st->direct[2][lane] = direct.z[i];
  }
}

// ---- The stages of one vertex (shade_group), each the scalar stage of the
// same name on eight lanes, run in path_stages.h's order ----

// Forced inline: shade_group was one function, and GCC (-O3) left the
// bigger stages as calls that pass the hit's vectors through memory.
#define GDVR_STAGE inline __attribute__((always_inline))

// Frame(n) (Duff et al.): the tangents s and t of the frame around unit n.
inline void vframe(V3 n, V3* s, V3* t) {
  const vf sign = (vf)(((vu)n.z & 0x80000000u) | 0x3f800000u);  // copysign(1, n.z)
  const vf a = -1.0f / (sign + n.z);
  const vf b = n.x * n.y * a;
  *s = V3{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
  *t = V3{b, sign + n.y * n.y * a, -n.y};
}

// What FrameScene::interaction and the BSDF's reflectance give a hit.
struct VertexHit {
  vu flags;    // the shape's kShape* flags
  V3 p;        // the hit point
  V3 n;        // the face normal, flip_normals applied
  V3 ns;       // the shading normal
  V3 albedo;   // the reflectance (a plastic's diffuse base), textured where the shape is
  vf offset_floor;
};

// FrameScene::interpolated_normal from the shading record's vertex normals:
// interpolated and normalised, the face normal where that fails, then
// flip_normals (the record's sign).
GDVR_STAGE V3 interpolated_normal_lanes(const RecordLanes& sr, vf b0, vf b1, vf b2, V3 n, vi smooth) {
  const V3 n0{sr.f[0], sr.f[1], sr.f[2]}, n1{sr.f[3], sr.f[4], sr.f[5]}, n2{sr.f[6], sr.f[7], sr.f[8]};
  V3 interp = n0 * b0 + n1 * b1 + n2 * b2;
  const vf l2 = vdot(interp, interp);
  interp = vsel3(l2 > 0.0f, interp * (1.0f / vsqrt(l2)), interp);
  const vi ok = finite(interp.x) & finite(interp.y) & finite(interp.z) & (vdot(interp, interp) > 0.5f);
  return vsel3(smooth & ok, interp * sr.f[9], n);
}

// A textured reflectance at the hit's uv (the mesh's, interpolated, or the
// barycentrics): a checkerboard here (Texture::eval_varying's arithmetic),
// other textures by eval_varying lane by lane.
GDVR_STAGE V3 textured_reflectance(const VectorSceneView& scene, const VectorBatchState* st, int k,
                                   const RecordLanes& sr, vu flags, vi textured, vf b0, vf b1, vf b2) {
  const vi has_uvs = (flags & kShapeHasUvs) != 0u;
  const vf u = vsel(has_uvs, sr.f[10] * b0 + sr.f[12] * b1 + sr.f[14] * b2, b1);
  const vf v = vsel(has_uvs, sr.f[11] * b0 + sr.f[13] * b1 + sr.f[15] * b2, b2);
  const vi checker = textured & ((flags & kShapeCheckerboard) != 0u);
  const vi other = textured & ~checker;
  V3 texture_value{splat(0.0f), splat(0.0f), splat(0.0f)};
  if (!_mm256_testz_si256((__m256i)checker, (__m256i)checker)) {
    uint32_t shape_lanes[kLanes];
    for (int i = 0; i < kLanes; ++i) shape_lanes[i] = checker[i] ? uint32_t(st->hit_shape[k + i]) : 0u;
    const RecordLanes c = load_records(scene.shape_checkerboard, shape_lanes);
    const vf tu = c.f[0] * u + c.f[1] * v + c.f[2], tv = c.f[3] * u + c.f[4] * v + c.f[5];  // UvTransform
    const vi mx = tu - vfloor(tu) > 0.5f, my = tv - vfloor(tv) > 0.5f;
    texture_value = vsel3(mx == my, V3{c.f[6], c.f[7], c.f[8]}, V3{c.f[9], c.f[10], c.f[11]});
  }
  if (!_mm256_testz_si256((__m256i)other, (__m256i)other)) {
    alignas(32) float r[kLanes], g[kLanes], bl[kLanes];
    for (int i = 0; i < kLanes; ++i) {
      r[i] = g[i] = bl[i] = 0.0f;
      if (!other[i]) continue;
      const Texture* texture = scene.shape_texture[st->hit_shape[k + i]];
      Vec2f uv;  // field by field: Vec2f's constructor is gdvr inline code
      uv.x = u[i];
      uv.y = v[i];
      const Rgb c = texture->eval_varying(uv);
      r[i] = c.r, g[i] = c.g, bl[i] = c.b;
    }
    texture_value = vsel3(other, V3{load<vf>(r), load<vf>(g), load<vf>(bl)}, texture_value);
  }
  return texture_value;
}

// FrameScene::interaction on a triangle of a mesh, from its record (and its
// shading record where the triangle interpolates vertex normals or is
// textured).
GDVR_STAGE VertexHit interaction_lanes(const VectorSceneView& scene, const VectorBatchState* st, int k, vi shade) {
  VertexHit hit;
  uint32_t tri[kLanes];
  alignas(32) uint32_t flag_lanes[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    const int32_t shape = shade[i] ? st->hit_shape[k + i] : 0;
    tri[i] = shade[i] ? scene.shape_first[shape] + uint32_t(st->hit_prim[k + i]) : 0u;
    flag_lanes[i] = shade[i] ? scene.shape_flags[shape] : 0u;
  }
  hit.flags = load<vu>(flag_lanes);
  const RecordLanes h = load_records(scene.triangles, tri);
  const V3 c0{h.f[0], h.f[1], h.f[2]}, c1{h.f[3], h.f[4], h.f[5]}, c2{h.f[6], h.f[7], h.f[8]};
  hit.n = V3{h.f[9], h.f[10], h.f[11]};
  hit.albedo = V3{h.f[12], h.f[13], h.f[14]};
  hit.offset_floor = vabs(h.f[15]);
  const vi smooth = shade & ((vi)h.f[15] < 0);  // the sign bit
  const vi textured = (hit.flags & kShapeTextured) != 0u;
  const vf b1 = load<vf>(&st->hit_u[k]), b2 = load<vf>(&st->hit_v[k]);
  const vf b0 = 1.0f - b1 - b2;
  hit.p = c0 * b0 + c1 * b1 + c2 * b2;
  hit.ns = hit.n;
  const vi needs_shading_record = smooth | textured;
  if (!_mm256_testz_si256((__m256i)needs_shading_record, (__m256i)needs_shading_record)) {
    const RecordLanes sr = load_records(scene.shading, tri);
    if (!_mm256_testz_si256((__m256i)smooth, (__m256i)smooth))
      hit.ns = interpolated_normal_lanes(sr, b0, b1, b2, hit.n, smooth);
    if (!_mm256_testz_si256((__m256i)textured, (__m256i)textured))
      hit.albedo = vsel3(textured, textured_reflectance(scene, st, k, sr, hit.flags, textured, b0, b1, b2), hit.albedo);
  }
  return hit;
}

// The shading frame, wo in it, and the BSDF parameters of the lanes that
// are not diffuse: what both the emitter connection and the BSDF sample
// read.
struct VertexBsdf {
  V3 fs, ft;         // the shading frame's tangents (ns its normal)
  vi mirrored;       // a two-sided BSDF hit from the back
  vf wo_front_z;     // wo's cosine, mirrored to the front
  vi conductor, plastic;
  bool any_conductor, any_plastic;
  V3 wo_local;       // si.wi mirrored to the front; set where a lane is a conductor or plastic
  VConductor cond;
  vf g1_wo;          // cond.g1_of(wo_local)
  VPlastic plas;
  vf f_o;            // plastic's Fresnel reflectance of wo
};

GDVR_STAGE VertexBsdf bsdf_lanes(const VectorSceneView& scene, const VectorBatchState* st, int k, vi shade,
                                 const VertexHit& hit) {
  VertexBsdf b{};
  vframe(hit.ns, &b.fs, &b.ft);
  const V3 wo_world = -load3(st->d, k);
  const vf wo_z = vdot(wo_world, hit.ns);
  // Mitsuba's twosided (bsdf.cpp, mirror_to_front): a query from the back
  // mirrors both directions to the front, and a sample back again.
  b.mirrored = ((hit.flags & kShapeTwoSided) != 0u) & ~(wo_z >= 0.0f);
  b.wo_front_z = vsel(b.mirrored, -wo_z, wo_z);
  b.conductor = shade & ((hit.flags & kShapeConductor) != 0u);
  b.any_conductor = !_mm256_testz_si256((__m256i)b.conductor, (__m256i)b.conductor);
  b.plastic = shade & ((hit.flags & kShapePlastic) != 0u);
  b.any_plastic = !_mm256_testz_si256((__m256i)b.plastic, (__m256i)b.plastic);
  if (b.any_conductor || b.any_plastic)
    b.wo_local = V3{vdot(wo_world, b.fs), vdot(wo_world, b.ft), b.wo_front_z};
  if (b.any_conductor) {
    uint32_t shape_lanes[kLanes];
    for (int i = 0; i < kLanes; ++i) shape_lanes[i] = b.conductor[i] ? uint32_t(st->hit_shape[k + i]) : 0u;
    const RecordLanes c = load_records(scene.shape_conductor, shape_lanes);
    b.cond.alpha_u = c.f[0];
    b.cond.alpha_v = c.f[1];
    b.cond.eta = V3{c.f[2], c.f[3], c.f[4]};
    b.cond.k = V3{c.f[5], c.f[6], c.f[7]};
    b.cond.specular = V3{c.f[8], c.f[9], c.f[10]};
    b.g1_wo = b.cond.g1_of(b.wo_local);
  }
  if (b.any_plastic) {
    uint32_t shape_lanes[kLanes];
    for (int i = 0; i < kLanes; ++i) shape_lanes[i] = b.plastic[i] ? uint32_t(st->hit_shape[k + i]) : 0u;
    const RecordLanes c = load_records(scene.shape_plastic, shape_lanes);
    b.plas.eta = c.f[0];
    b.plas.rcp_eta = c.f[1];
    b.plas.inv_eta2 = c.f[2];
    b.plas.specular_weight = c.f[3];
    b.plas.specular = V3{c.f[4], c.f[5], c.f[6]};
    b.f_o = b.plas.fresnel(b.wo_front_z);
  }
  return b;
}

// sample_emitter's EmitterSample on eight lanes. `sampled`: where a sample
// was made (elsewhere its weight may be garbage).
struct EmitterLanes {
  V3 d{}, weight{};
  vf dist{}, pdf{};
  vi sampled{}, delta{};
};

// Where every emitter is a flat-shaded mesh light: a uniform emitter, an
// area-weighted triangle, a point on it (area_emitter.cpp).
GDVR_STAGE EmitterLanes sample_triangle_emitters(const VectorSceneView& scene, vi shade, V3 p, vf u_select, vf ux,
                                                 vf uy) {
  EmitterLanes es;
  uint32_t etri[kLanes];
  alignas(32) float u_tri_lanes[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    etri[i] = 0;
    u_tri_lanes[i] = 0.0f;
    if (!shade[i]) continue;
    const float scaled = u_select[i] * float(scene.emitter_count);
    uint32_t index = uint32_t(scaled);
    if (index > scene.emitter_count - 1) index = scene.emitter_count - 1;
    float u_tri;
    const size_t t = scene.emitter_choice[index]->sample(ux[i], &u_tri);
    etri[i] = scene.emitter_first[index] + uint32_t(t);
    u_tri_lanes[i] = u_tri;
  }
  const RecordLanes e = load_records(scene.emitter_triangles, etri);
  const V3 lp0{e.f[0], e.f[1], e.f[2]}, lp1{e.f[3], e.f[4], e.f[5]}, lp2{e.f[6], e.f[7], e.f[8]};
  const V3 ln{e.f[9], e.f[10], e.f[11]}, radiance{e.f[12], e.f[13], e.f[14]};
  const vf area = e.f[15];
  const vf tt = safe_vsqrt(1.0f - load<vf>(u_tri_lanes));  // square_to_uniform_triangle
  const vf lb1 = 1.0f - tt, lb2 = tt * uy;
  const V3 lp = lp0 * (1.0f - lb1 - lb2) + lp1 * lb1 + lp2 * lb2;
  const V3 to_light = lp - p;
  const vf dist2 = vdot(to_light, to_light);
  es.dist = vsqrt(dist2);
  const vf abs_dn = vabs(vdot(to_light, ln));
  const vf pdf_solid_angle = vsel(abs_dn > 0.0f, dist2 * (es.dist / (area * abs_dn)), splat(0.0f));
  es.sampled = (es.dist > 0.0f) & (pdf_solid_angle > 0.0f) & finite(pdf_solid_angle);
  es.d = to_light * (1.0f / es.dist);
  es.pdf = pdf_solid_angle * scene.select_pdf;
  es.weight = vsel3(vdot(ln, es.d) < 0.0f, radiance * (1.0f / es.pdf), V3{splat(0.0f), splat(0.0f), splat(0.0f)});
  return es;
}

// Lanes whose emitter (`index`) is a sphere light seen from outside: the
// cone sampling of sample_sphere_emitter_point (area_emitter.cpp). Returns
// those lanes; *es holds their samples, zero elsewhere.
GDVR_STAGE vi sample_sphere_emitters(const VectorSceneView& scene, vi shade, V3 p, const uint32_t index[kLanes], vf ux,
                                     vf uy, EmitterLanes* es) {
  const RecordLanes sp = load_records(scene.emitter_spheres, index);
  const V3 center{sp.f[0], sp.f[1], sp.f[2]}, radiance{sp.f[4], sp.f[5], sp.f[6]};
  const vf radius = sp.f[3], flip = sp.f[7];
  const V3 dc = center - p;
  const vf dc2 = vdot(dc, dc), r2 = radius * radius;
  const vi here = shade & (radius > 0.0f) & (dc2 > r2 * (1.0f + 1e-5f));
  if (_mm256_testz_si256((__m256i)here, (__m256i)here)) return here;
  vf sin_c, cos_c, sin_phi, cos_phi;
  sphere_point_in_cone(r2 / dc2, uy, &sin_c, &cos_c);
  vsincos_turns(ux, &sin_phi, &cos_phi);
  const V3 wz = dc * (1.0f / vsqrt(dc2));  // Frame(wz), z towards the centre
  V3 fx, fy;
  vframe(wz, &fx, &fy);
  V3 ln = fx * (-sin_c * cos_phi) + fy * (-sin_c * sin_phi) + wz * (-cos_c);
  const V3 lp = center + ln * radius;
  const vd dc2d = to_double(dc2), r2d = to_double(radius) * to_double(radius);
  const vd diff = dc2d - r2d;
  const vf pdf_solid_angle =
      to_single((dc2d + vsqrt_d(dc2d * vsel_d(0.0 < diff, diff, vd{}))) / (2.0 * double(kPi) * r2d));
  ln = vsel3(flip < 0.0f, -ln, ln);
  const V3 to_light = lp - p;
  const vf sdist = vsqrt(vdot(to_light, to_light));
  const vi ok = (sdist > 0.0f) & (pdf_solid_angle > 0.0f) & finite(pdf_solid_angle);
  const V3 sd = to_light * (1.0f / sdist);
  const vf spdf = pdf_solid_angle * scene.select_pdf;
  const V3 zero{splat(0.0f), splat(0.0f), splat(0.0f)};
  es->d = vsel3(here, sd, zero);
  es->dist = vsel(here, sdist, splat(0.0f));
  es->pdf = vsel(here, spdf, splat(0.0f));
  es->weight = vsel3(here & ok & (vdot(ln, sd) < 0.0f), radiance * (1.0f / spdf), zero);
  return here;
}

// Lanes whose emitter is the environment map (and not taken yet, `here`):
// sample_envmap_emitter (environment_emitter.cpp). Returns `here` with them.
GDVR_STAGE vi sample_envmap_emitter_lanes(const VectorSceneView& scene, vi shade, vi here, const uint32_t index[kLanes],
                                          vf ux, vf uy, EmitterLanes* es) {
  const vi env = shade & ~here & ((vu)load<vi>(index) == scene.envmap->emitter);
  if (_mm256_testz_si256((__m256i)env, (__m256i)env)) return here;
  V3 env_d, env_weight;
  vf env_pdf;
  const vi ok = sample_envmap(*scene.envmap, scene.select_pdf, env, ux, uy, &env_d, &env_pdf, &env_weight);
  const V3 zero{splat(0.0f), splat(0.0f), splat(0.0f)};
  es->d = vsel3(ok, env_d, es->d);
  es->dist = vsel(ok, splat(kInfinity), es->dist);
  es->pdf = vsel(ok, env_pdf, es->pdf);
  es->weight = vsel3(ok, env_weight, vsel3(env, zero, es->weight));
  return here | env;
}

// The lanes `elsewhere` (points, spots, directional lights, smooth area
// lights, a point inside a sphere) by FrameScene's own sampling, lane by lane.
GDVR_STAGE void sample_emitters_in_frame_scene(const VectorSceneView& scene, vi elsewhere, vi here, V3 p, vf u_select,
                                               vf ux, vf uy, EmitterLanes* es) {
  alignas(32) float d[3][kLanes], w[3][kLanes], dist_lanes[kLanes], pdf_lanes[kLanes];
  alignas(32) int32_t delta_lanes[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    EmitterSampleLane lane{};
    if (elsewhere[i]) {
      const float pl[3] = {p.x[i], p.y[i], p.z[i]};
      scene.sample_emitter(scene.frame_scene, pl, u_select[i], ux[i], uy[i], &lane);
    }
    d[0][i] = lane.d[0], d[1][i] = lane.d[1], d[2][i] = lane.d[2];
    w[0][i] = lane.weight[0], w[1][i] = lane.weight[1], w[2][i] = lane.weight[2];
    dist_lanes[i] = lane.dist;
    pdf_lanes[i] = lane.pdf;
    delta_lanes[i] = lane.delta;
  }
  es->d = vsel3(here, es->d, V3{load<vf>(d[0]), load<vf>(d[1]), load<vf>(d[2])});
  es->weight = vsel3(here, es->weight, V3{load<vf>(w[0]), load<vf>(w[1]), load<vf>(w[2])});
  es->dist = vsel(here, es->dist, load<vf>(dist_lanes));
  es->pdf = vsel(here, es->pdf, load<vf>(pdf_lanes));
  es->delta = load<vi>(delta_lanes);
}

// sample_emitter with the three numbers it draws: a uniform emitter, then
// its kind's sample (core/emitter/), here where the kernel has the kind's
// records, else by FrameScene.
GDVR_STAGE EmitterLanes sample_emitter_lanes(const VectorSceneView& scene, vi shade, V3 p, vf u_select, vf ux, vf uy) {
  if (scene.emitter_triangles) return sample_triangle_emitters(scene, shade, p, u_select, ux, uy);
  EmitterLanes es;
  vi here = vi{};
  alignas(32) uint32_t index[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    const uint32_t e = uint32_t(u_select[i] * float(scene.emitter_count));
    index[i] = shade[i] ? (e < scene.emitter_count - 1 ? e : scene.emitter_count - 1) : 0u;
  }
  if (scene.emitter_spheres) here = sample_sphere_emitters(scene, shade, p, index, ux, uy, &es);
  if (scene.envmap) here = sample_envmap_emitter_lanes(scene, shade, here, index, ux, uy, &es);
  const vi elsewhere = shade & ~here;
  if (!_mm256_testz_si256((__m256i)elsewhere, (__m256i)elsewhere))
    sample_emitters_in_frame_scene(scene, elsewhere, here, p, u_select, ux, uy, &es);
  es.sampled = shade;  // the weight is zero where nothing was sampled
  return es;
}

// connect_emitter: the BSDF towards the emitter sample, MIS, and the shadow
// ray with its contribution, left for the driver to trace.
GDVR_STAGE void connect_emitter_lanes(VectorBatchState* st, int k, vi shade, V3 throughput, const VertexHit& hit,
                                      const VertexBsdf& b, const EmitterLanes& es) {
  const vf wl_z = vsel(b.mirrored, -vdot(es.d, hit.ns), vdot(es.d, hit.ns));
  // diffuse_eval_pdf's test is `wo.z <= 0 || wi.z <= 0`, kept as written for NaN.
  const vi diffuse_lit = ~(b.wo_front_z <= 0.0f) & ~(wl_z <= 0.0f);
  vf bsdf_pdf = kInvPi * wl_z;
  V3 f = hit.albedo * bsdf_pdf;
  if (b.any_conductor) {
    V3 fc;
    vf pc;
    b.cond.eval_pdf(b.wo_local, b.g1_wo, V3{vdot(es.d, b.fs), vdot(es.d, b.ft), wl_z}, &fc, &pc);
    f = vsel3(b.conductor, fc, f);
    bsdf_pdf = vsel(b.conductor, pc, bsdf_pdf);
  }
  if (b.any_plastic) {
    V3 fp;
    vf pp;
    b.plas.eval_pdf(hit.albedo, b.wo_front_z, b.f_o, wl_z, &fp, &pp);
    f = vsel3(b.plastic, fp, f);
    bsdf_pdf = vsel(b.plastic, pp, bsdf_pdf);
  }
  const vi lit = shade & es.sampled & ~is_black(es.weight) & (b.conductor | b.plastic | diffuse_lit);
  const vi connect = lit & ~is_black(f);
  const vf w = vsel(es.delta, splat(1.0f), mis_power(es.pdf, bsdf_pdf));
  store3(st->shadow_contribution, k, throughput * f * es.weight * w, connect);
  // shadow_ray(): aimed from the offset origin at the emitter point.
  const V3 shadow_o = offset_p(hit.p, hit.offset_floor, hit.n, es.d);
  const V3 to_target = (hit.p + es.d * es.dist) - shadow_o;
  const vf to_len = vsqrt(vdot(to_target, to_target));
  const vi finite_dist = ~(es.dist == kInfinity);
  const vi reaches = finite_dist & (to_len > 0.0f);
  store3(st->shadow_o, k, shadow_o, connect);
  store3(st->shadow_d, k, vsel3(reaches, to_target * (1.0f / to_len), es.d), connect);
  store1(st->shadow_tmax, k,
         vsel(finite_dist, vsel(reaches, to_len * (1.0f - kShadowEpsilon), splat(0.0f)), splat(kInfinity)), connect);
  store1(st->shadow_pending, k, connect, shade);
}

// sample_bsdf_drawn with the numbers draw_bsdf_numbers drew: the bounce's
// direction, weight and pdf, the next ray and the MIS state it carries.
// Updates *throughput; returns the lanes whose path goes on.
GDVR_STAGE vi sample_bsdf_lanes(VectorBatchState* st, int k, vi shade, const VertexHit& hit, const VertexBsdf& b,
                                vf u_lobe, vf vx, vf vy, V3* throughput) {
  V3 wi = cosine_hemisphere(vx, vy);
  vf pdf = kInvPi * wi.z;
  vi alive = shade & ~b.conductor & ~b.plastic & ~(b.wo_front_z <= 0.0f) & (pdf > 0.0f) & ~is_black(hit.albedo);
  V3 bsdf_weight = hit.albedo;
  vi delta_lobe = vi{};
  if (b.any_plastic) {
    V3 wi_p, weight_p;
    vf pdf_p;
    vi delta_p;
    const vi ok = b.plas.sample(hit.albedo, b.wo_local, b.f_o, u_lobe, wi, &wi_p, &weight_p, &pdf_p, &delta_p);
    alive |= b.plastic & ok & ~is_black(weight_p);
    wi = vsel3(b.plastic, wi_p, wi);
    bsdf_weight = vsel3(b.plastic, weight_p, bsdf_weight);
    pdf = vsel(b.plastic, pdf_p, pdf);
    delta_lobe = b.plastic & delta_p;
  }
  if (b.any_conductor) {
    V3 wi_c, weight_c;
    vf pdf_c;
    const vi ok = b.cond.sample(b.wo_local, b.g1_wo, vx, vy, &wi_c, &weight_c, &pdf_c);
    alive |= b.conductor & ok & ~is_black(weight_c);
    wi = vsel3(b.conductor, wi_c, wi);
    bsdf_weight = vsel3(b.conductor, weight_c, bsdf_weight);
    pdf = vsel(b.conductor, pdf_c, pdf);
  }
  *throughput = vsel3(alive, *throughput * bsdf_weight, *throughput);
  const V3 next_d = b.fs * wi.x + b.ft * wi.y + hit.ns * vsel(b.mirrored, -wi.z, wi.z);  // Frame::to_world
  store3(st->o, k, offset_p(hit.p, hit.offset_floor, hit.n, next_d), alive);
  store3(st->d, k, next_d, alive);
  store1(st->tmin, k, splat(0.0f), alive);
  store1(st->tmax, k, splat(kInfinity), alive);
  store3(st->prev_p, k, hit.p, alive);
  store1(st->prev_pdf, k, pdf, alive);
  store1(st->prev_delta, k, delta_lobe, alive);
  return alive;
}

// Russian roulette (the kernel's BSDFs leave eta as it is), then the path's
// new throughput, depth and whether it continues.
GDVR_STAGE void russian_roulette_lanes(const VectorSceneView& scene, VectorBatchState* st, int k, vi shade, vi depth,
                                       vi alive, V3 throughput, VPcg32& rng) {
  const vf throughput_max = vmax(throughput.x, vmax(throughput.y, throughput.z));
  alive &= throughput_max > 0.0f;
  const vi rr = alive & (depth + 1 >= scene.rr_depth);
  const vf eta = load<vf>(&st->eta[k]);
  const vf q = vmin(throughput_max * eta * eta, splat(1.0f));
  const vf u = rng.next_float(rr);
  alive &= ~rr | (u < q);
  throughput = vsel3(rr & alive, throughput * (1.0f / q), throughput);
  store3(st->throughput, k, throughput, shade);
  store1(st->depth, k, depth + 1, alive);
  store1(st->continues, k, alive, shade);
}

// One vertex on the lanes of group k marked in `shade`. The random numbers
// are drawn here, in the scalar stages' order, so that every lane's stream
// stays the scalar path's.
void shade_group(const VectorSceneView& scene, VectorBatchState* st, int k, vi shade) {
  VPcg32 rng{load<vu64>(&st->rng_state[k]), load<vu64>(&st->rng_inc[k])};
  V3 throughput = load3(st->throughput, k);
  const vi depth = load<vi>(&st->depth[k]);
  const VertexHit hit = interaction_lanes(scene, st, k, shade);
  const VertexBsdf bsdf = bsdf_lanes(scene, st, k, shade, hit);

  const vf u_select = rng.next_float(shade);
  const vf ux = rng.next_float(shade), uy = rng.next_float(shade);
  const EmitterLanes es = sample_emitter_lanes(scene, shade, hit.p, u_select, ux, uy);
  connect_emitter_lanes(st, k, shade, throughput, hit, bsdf, es);

  const vf u_lobe = rng.next_float(shade);  // read by plastic alone (one lobe elsewhere)
  const vf vx = rng.next_float(shade), vy = rng.next_float(shade);
  const vi alive = sample_bsdf_lanes(st, k, shade, hit, bsdf, u_lobe, vx, vy, &throughput);
  russian_roulette_lanes(scene, st, k, shade, depth, alive, throughput, rng);
  store(&st->rng_state[k], rng.state);
}
#undef GDVR_STAGE

}  // namespace

void GDVR_ENVIRONMENT_KERNEL(const VectorSceneView& scene, VectorBatchState* state, const int32_t* lanes, int n,
                             bool hide_camera_rays) {
  for (int k = 0; k < n; k += kLanes) add_environment_group(scene, state, lanes + k, n - k, hide_camera_rays);
}

void GDVR_VERTEX_KERNEL(const VectorSceneView& scene, VectorBatchState* state) {
  for (int k = 0; k < kVectorBatch; k += kLanes) {
    const vi shade = load<vi>(&state->shade[k]) != 0;
    if (_mm256_testz_si256((__m256i)shade, (__m256i)shade)) continue;
    shade_group(scene, state, k, shade);
  }
}

}  // namespace gdvr
