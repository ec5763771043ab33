// The diffuse batch's vertex on eight paths at once (diffuse_batch_state.h),
// compiled once per instruction set: diffuse_vertex_avx2.cpp (-mavx2) and
// diffuse_vertex_avx512.cpp (AVX-512F/VL/DQ on the same 8-lane vectors:
// masks, and the 64-bit multiply of PCG32 in one instruction), each defining
// GDVR_DIFFUSE_KERNEL as its entry point's name. diffuse_batch.cpp runs the
// best one the CPU has. Everything it uses is its own or an intrinsic: see
// diffuse_batch_state.h for why.
//
// Each step is the scalar code's in the same order, turned into lane masks:
//   FrameScene::interaction (a triangle of a mesh), Frame,
//   sample_emitter -> FrameScene::sample_emitter_direction (area emitters),
//   connect_emitter -> diffuse_eval_pdf (two-sided: mirror_to_front),
//   mis_power, shadow_ray, draw_bsdf_numbers, sample_bsdf_drawn ->
//   diffuse_sample, square_to_cosine_hemisphere, spawn_ray,
//   russian_roulette_survival.
// No multiply-add is fused (-ffp-contract=off for the whole build), so the
// vector and scalar forms round alike; DiffuseBatchTest checks every kernel
// against the scalar batch bit for bit.
#ifndef GDVR_DIFFUSE_KERNEL
#error "define GDVR_DIFFUSE_KERNEL (the entry point's name) before including this file"
#endif

#include <immintrin.h>

// The generators' 64-bit words take 512-bit vectors, which GCC warns change
// the calling convention without AVX-512; they never cross a call (every
// function here is inline in this file).
#pragma GCC diagnostic ignored "-Wpsabi"

#include <cstdint>
#include <cstring>

#include "core/math/distribution.h"
#include "core/math/vec.h"
#include "core/render/diffuse_batch_state.h"
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
inline V3 load3(const float (*a)[kDiffuseBatch], int k) {
  return {load<vf>(&a[0][k]), load<vf>(&a[1][k]), load<vf>(&a[2][k])};
}
// Stores the lanes in m; the others keep what they held.
inline void store3(float (*a)[kDiffuseBatch], int k, V3 v, vi m) {
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

void shade_group(const DiffuseSceneView& scene, DiffuseBatchState* st, int k, vi shade) {
  VPcg32 rng{load<vu64>(&st->rng_state[k]), load<vu64>(&st->rng_inc[k])};
  V3 throughput = load3(st->throughput, k);
  const vi depth = load<vi>(&st->depth[k]);

  // ---- The hit (FrameScene::interaction) ----
  uint32_t tri[kLanes];
  alignas(32) uint32_t flag_lanes[kLanes];
  for (int i = 0; i < kLanes; ++i) {
    const int32_t shape = shade[i] ? st->hit_shape[k + i] : 0;
    tri[i] = shade[i] ? scene.shape_first[shape] + uint32_t(st->hit_prim[k + i]) : 0u;
    flag_lanes[i] = shade[i] ? scene.shape_flags[shape] : 0u;
  }
  const vu flags = load<vu>(flag_lanes);
  const RecordLanes h = load_records(scene.triangles, tri);
  const V3 c0{h.f[0], h.f[1], h.f[2]}, c1{h.f[3], h.f[4], h.f[5]}, c2{h.f[6], h.f[7], h.f[8]};
  const V3 n{h.f[9], h.f[10], h.f[11]};
  V3 albedo{h.f[12], h.f[13], h.f[14]};
  const vf offset_floor = vabs(h.f[15]);
  const vi smooth = shade & ((vi)h.f[15] < 0);  // the sign bit
  const vi textured = (flags & kShapeTextured) != 0u;
  const vf b1 = load<vf>(&st->hit_u[k]), b2 = load<vf>(&st->hit_v[k]);
  const vf b0 = 1.0f - b1 - b2;
  const V3 p = c0 * b0 + c1 * b1 + c2 * b2;
  V3 ns = n;
  const vi needs_shading_record = smooth | textured;
  if (!_mm256_testz_si256((__m256i)needs_shading_record, (__m256i)needs_shading_record)) {
    const RecordLanes sr = load_records(scene.shading, tri);
    // The shading normal: the face normal, or (FrameScene::interpolated_normal)
    // the vertex normals interpolated and normalised, the face normal where
    // that fails, then flip_normals.
    if (!_mm256_testz_si256((__m256i)smooth, (__m256i)smooth)) {
      const V3 n0{sr.f[0], sr.f[1], sr.f[2]}, n1{sr.f[3], sr.f[4], sr.f[5]}, n2{sr.f[6], sr.f[7], sr.f[8]};
      V3 interp = n0 * b0 + n1 * b1 + n2 * b2;
      const vf l2 = vdot(interp, interp);
      interp = vsel3(l2 > 0.0f, interp * (1.0f / vsqrt(l2)), interp);
      const vi ok = finite(interp.x) & finite(interp.y) & finite(interp.z) & (vdot(interp, interp) > 0.5f);
      ns = vsel3(smooth & ok, interp * sr.f[9], n);
    }
    // A textured reflectance at the hit's uv (the mesh's, interpolated, or
    // the barycentrics), evaluated lane by lane.
    if (!_mm256_testz_si256((__m256i)textured, (__m256i)textured)) {
      const vi has_uvs = (flags & kShapeHasUvs) != 0u;
      const vf u = vsel(has_uvs, sr.f[10] * b0 + sr.f[12] * b1 + sr.f[14] * b2, b1);
      const vf v = vsel(has_uvs, sr.f[11] * b0 + sr.f[13] * b1 + sr.f[15] * b2, b2);
      alignas(32) float r[kLanes], g[kLanes], bl[kLanes];
      for (int i = 0; i < kLanes; ++i) {
        r[i] = g[i] = bl[i] = 0.0f;
        if (!textured[i]) continue;
        const Texture* texture = scene.shape_texture[st->hit_shape[k + i]];
        Vec2f uv;  // field by field: Vec2f's constructor is gdvr inline code
        uv.x = u[i];
        uv.y = v[i];
        const Rgb c = texture->eval_varying(uv);
        r[i] = c.r, g[i] = c.g, bl[i] = c.b;
      }
      albedo = vsel3(textured, V3{load<vf>(r), load<vf>(g), load<vf>(bl)}, albedo);
    }
  }
  // Frame(ns) (Duff et al.).
  const vf sign = (vf)(((vu)ns.z & 0x80000000u) | 0x3f800000u);  // copysign(1, ns.z)
  const vf a = -1.0f / (sign + ns.z);
  const vf b = ns.x * ns.y * a;
  const V3 fs{1.0f + sign * ns.x * ns.x * a, sign * b, -sign * ns.x};
  const V3 ft{b, sign + ns.y * ns.y * a, -ns.y};
  const V3 wo_world = -load3(st->d, k);
  const vf wo_z = vdot(wo_world, ns);
  // Mitsuba's twosided (bsdf.cpp, mirror_to_front): a query from the back
  // mirrors both directions to the front, and a sample back again.
  const vi mirrored = ((flags & kShapeTwoSided) != 0u) & ~(wo_z >= 0.0f);
  const vf wo_front_z = vsel(mirrored, -wo_z, wo_z);

  // ---- sample_emitter: a uniform emitter, an area-weighted triangle, a point ----
  const vf u_select = rng.next_float(shade);
  const vf ux = rng.next_float(shade), uy = rng.next_float(shade);
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
  const vf dist = vsqrt(dist2);
  const vf abs_dn = vabs(vdot(to_light, ln));
  const vf pdf_solid_angle = vsel(abs_dn > 0.0f, dist2 * (dist / (area * abs_dn)), splat(0.0f));
  const vi sampled = (dist > 0.0f) & (pdf_solid_angle > 0.0f) & finite(pdf_solid_angle);
  const V3 es_d = to_light * (1.0f / dist);
  const vf es_pdf = pdf_solid_angle * scene.select_pdf;
  const V3 weight = vsel3(vdot(ln, es_d) < 0.0f, radiance * (1.0f / es_pdf), V3{splat(0.0f), splat(0.0f), splat(0.0f)});

  // ---- connect_emitter: the diffuse BSDF towards it, MIS, the shadow ray ----
  const vf wl_z = vsel(mirrored, -vdot(es_d, ns), vdot(es_d, ns));
  // diffuse_eval_pdf's test is `wo.z <= 0 || wi.z <= 0`, kept as written for NaN.
  const vi lit = shade & sampled & ~is_black(weight) & ~(wo_front_z <= 0.0f) & ~(wl_z <= 0.0f);
  const vf bsdf_pdf = kInvPi * wl_z;
  const V3 f = albedo * bsdf_pdf;
  const vi connect = lit & ~is_black(f);
  const vf w = mis_power(es_pdf, bsdf_pdf);
  store3(st->shadow_contribution, k, throughput * f * weight * w, connect);
  store3(st->shadow_o, k, offset_p(p, offset_floor, n, es_d), connect);
  store3(st->shadow_d, k, es_d, connect);
  store1(st->shadow_tmax, k, dist * (1.0f - kShadowEpsilon), connect);
  store1(st->shadow_pending, k, connect, shade);

  // ---- draw_bsdf_numbers, then sample_bsdf_drawn ----
  (void)rng.next_float(shade);  // u_lobe: one lobe
  const vf vx = rng.next_float(shade), vy = rng.next_float(shade);
  const V3 wi = cosine_hemisphere(vx, vy);
  const vf pdf = kInvPi * wi.z;
  vi alive = shade & ~(wo_front_z <= 0.0f) & (pdf > 0.0f) & ~is_black(albedo);
  throughput = vsel3(alive, throughput * albedo, throughput);
  const V3 next_d = fs * wi.x + ft * wi.y + ns * vsel(mirrored, -wi.z, wi.z);  // Frame::to_world
  store3(st->o, k, offset_p(p, offset_floor, n, next_d), alive);
  store3(st->d, k, next_d, alive);
  store1(st->tmin, k, splat(0.0f), alive);
  store1(st->tmax, k, splat(kInfinity), alive);
  store3(st->prev_p, k, p, alive);
  store1(st->prev_pdf, k, pdf, alive);
  store1(st->prev_delta, k, vi{}, alive);
  // Russian roulette (eta stays 1 on a diffuse path).
  const vf throughput_max = vmax(throughput.x, vmax(throughput.y, throughput.z));
  alive &= throughput_max > 0.0f;
  const vi rr = alive & (depth + 1 >= scene.rr_depth);
  const vf q = vmin(throughput_max * 1.0f * 1.0f, splat(1.0f));
  const vf u = rng.next_float(rr);
  alive &= ~rr | (u < q);
  throughput = vsel3(rr & alive, throughput * (1.0f / q), throughput);
  store3(st->throughput, k, throughput, shade);
  store1(st->depth, k, depth + 1, alive);
  store1(st->continues, k, alive, shade);
  store(&st->rng_state[k], rng.state);
}

}  // namespace

void GDVR_DIFFUSE_KERNEL(const DiffuseSceneView& scene, DiffuseBatchState* state) {
  for (int k = 0; k < kDiffuseBatch; k += kLanes) {
    const vi shade = load<vi>(&state->shade[k]) != 0;
    if (_mm256_testz_si256((__m256i)shade, (__m256i)shade)) continue;
    shade_group(scene, state, k, shade);
  }
}

}  // namespace gdvr
