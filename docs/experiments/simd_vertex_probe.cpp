// How much would SIMD across paths save on gdvr's own code? A probe for
// issue 2's performance targets, not part of the renderer
// (docs/experiments/README.md has the commands and what they measured).
//
// One diffuse path vertex of a Cornell box, the only kind of vertex cbox has,
// with the same arithmetic in the same order as core/: the hit's shading
// from the mesh (FrameScene::interaction for a static triangle), the frame,
// next-event estimation towards a quad light (triangle pick, uniform point,
// area-to-solid-angle pdf), the diffuse BSDF and the power heuristic, the
// shadow ray, the cosine-weighted bounce through the concentric disk, Russian
// roulette, the next ray and seven PCG32 numbers. No ray is traced: this is
// the code between two Embree calls. It runs in three forms:
//   - scalar: one path at a time over an array of path structs, as
//     path_batch.cpp does, calling gdvr's own frame, generator, warps, MIS,
//     distribution and ray offsets (fused into one loop: the scalar form's
//     best case);
//   - simd, struct of arrays: LANES paths at a time, state held as one array
//     per field (GCC vector extensions; the ISA is what the compiler is told);
//   - simd, gathered structs: the same vector code on today's path structs,
//     gathered into vectors and scattered back lane by lane.
// All three must give the same bits (the probe checks and fails otherwise;
// -ffp-contract=off keeps GCC from fusing multiply-adds differently in each).
//
// From the repository root:
//   g++ -std=c++17 -O3 -fno-math-errno -ffp-contract=off -Wno-psabi -I. -DLANES=4 -o probe
//       docs/experiments/simd_vertex_probe.cpp core/math/distribution.cpp core/math/alias_table.cpp
//   ... -DLANES=8 -march=x86-64-v3      (AVX2)
//   ... -DLANES=16 -march=x86-64-v4     (AVX-512)
//   ... -DLANES=8 -DRECORDS -march=x86-64-v3 or -v4   (scene loads as whole
//       per-triangle records, transposed, instead of gathers)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

#include <immintrin.h>

#include "core/math/distribution.h"
#include "core/math/frame.h"
#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/math/vec.h"
#include "core/render/ray.h"
#include "core/render/russian_roulette.h"

namespace {

using gdvr::Rgb;
using gdvr::Vec2f;
using gdvr::Vec3f;

constexpr int kPaths = 64;  // paths in flight per thread, as path_batch.h
#ifndef LANES
#define LANES 8
#endif
constexpr int kLanes = LANES;
constexpr int kRrDepth = 5;

// ---------------------------------------------------------------- scalar form
// The quad light: two triangles picked by a Distribution1D, as FrameScene does.
// One cache line per triangle, for the vector form's RECORDS layout: what a
// vertex reads of its triangle, loaded whole and transposed instead of
// gathered field by field.
struct alignas(64) TriangleRecord {
  Vec3f p0, p1, p2, n;
  Rgb albedo;  // unused for the light
  float offset_floor;
};
static_assert(sizeof(TriangleRecord) == 16 * sizeof(float));

struct Light {
  Vec3f p0[2], p1[2], p2[2], n[2];
  TriangleRecord records[2];
  gdvr::Distribution1D triangles{std::vector<float>{1.0f, 1.0f}};
  float area;  // of the whole quad
  Rgb radiance;
};

// The walls, as FrameScene holds a static mesh: indices, positions, face
// normals and offset floors precomputed per triangle, and here the BSDF's
// constant reflectance per triangle.
struct Mesh {
  std::vector<uint32_t> indices;
  std::vector<Vec3f> positions, face_normals;
  std::vector<float> offset_floors;
  std::vector<Rgb> albedo;
  std::vector<TriangleRecord> records;  // the same, one record per triangle
};

// What a vertex reads and writes, as PathState holds it (the fields used).
struct ScalarPath {
  gdvr::Pcg32 rng;
  uint32_t prim;  // the hit: triangle and barycentrics, as Embree returns them
  float b1, b2;
  Vec3f ray_d;
  Rgb throughput;
  int depth;
  bool alive;
  // outputs
  Vec3f shadow_o, shadow_d;
  Rgb contribution;
  Vec3f next_o, next_d;
  float shadow_tmax;
  bool shadow_pending;
};

// The vector form reads and writes the generator's two words (state, then
// the odd increment).
static_assert(sizeof(gdvr::Pcg32) == 2 * sizeof(uint64_t) && std::is_trivially_copyable_v<gdvr::Pcg32>);
inline void pcg_words(const gdvr::Pcg32& rng, uint64_t w[2]) { std::memcpy(w, &rng, sizeof rng); }
inline void set_pcg_words(gdvr::Pcg32* rng, const uint64_t w[2]) {
  std::memcpy(static_cast<void*>(rng), w, sizeof *rng);
}

// Steps of FrameScene::sample_emitter_direction (one area emitter),
// connect_emitter with the diffuse BSDF, sample_bsdf_drawn and Russian roulette.
void scalar_vertex(const Light& light, const Mesh& mesh, ScalarPath* st) {
  // The hit (FrameScene::interaction, a flat triangle of a static mesh).
  gdvr::SurfaceInteraction si;
  const uint32_t prim = st->prim;
  const uint32_t i0 = mesh.indices[3 * prim], i1 = mesh.indices[3 * prim + 1], i2 = mesh.indices[3 * prim + 2];
  const float b1 = st->b1, b2 = st->b2, b0 = 1.0f - b1 - b2;
  si.p = mesh.positions[i0] * b0 + mesh.positions[i1] * b1 + mesh.positions[i2] * b2;
  si.offset_floor = mesh.offset_floors[prim];
  si.n = mesh.face_normals[prim];
  si.sh_frame = gdvr::Frame(si.n);
  si.uv = {b1, b2};
  const Rgb albedo = mesh.albedo[prim];
  const Vec3f wo = si.sh_frame.to_local(-st->ray_d);
  st->shadow_pending = false;
  if (wo.z <= 0.0f) {  // the diffuse BSDF has nothing from below
    st->alive = false;
    return;
  }
  // Next-event estimation.
  const float u_select = st->rng.next_float();
  const float ux = st->rng.next_float(), uy = st->rng.next_float();
  (void)u_select;  // one emitter
  const float select_pdf = 1.0f / 1.0f;
  float u_tri;
  const size_t t = light.triangles.sample(ux, &u_tri);
  const Vec2f lb = gdvr::square_to_uniform_triangle({u_tri, uy});
  const Vec3f lp = light.p0[t] * (1.0f - lb.x - lb.y) + light.p1[t] * lb.x + light.p2[t] * lb.y;
  const Vec3f d = lp - si.p;
  const float dist2 = gdvr::length_squared(d);
  const float dist = std::sqrt(dist2);
  const float abs_dn = std::abs(gdvr::dot(d, light.n[t]));
  const float pdf_solid_angle = abs_dn > 0 ? dist2 * (dist / (light.area * abs_dn)) : 0.0f;
  if (dist > 0 && pdf_solid_angle > 0 && std::isfinite(pdf_solid_angle)) {
    const Vec3f dir = d * (1.0f / dist);
    const float pdf = pdf_solid_angle * select_pdf;
    if (gdvr::dot(light.n[t], dir) < 0) {
      const Rgb weight = light.radiance / pdf;
      const Vec3f wl = si.sh_frame.to_local(dir);
      if (wl.z > 0.0f) {
        const float bsdf_pdf = gdvr::square_to_cosine_hemisphere_pdf(wl);
        const Rgb f = albedo * bsdf_pdf;
        const float w = gdvr::mis_power(pdf, bsdf_pdf);
        const gdvr::Ray shadow = si.spawn_ray(dir);
        st->shadow_o = shadow.o;
        st->shadow_d = shadow.d;
        st->shadow_tmax = dist * (1.0f - gdvr::kShadowEpsilon);
        st->contribution = st->throughput * f * weight * w;
        st->shadow_pending = true;
      }
    }
  }
  // The bounce.
  const float u_lobe = st->rng.next_float();
  (void)u_lobe;  // one lobe
  const float vx = st->rng.next_float(), vy = st->rng.next_float();
  const Vec3f wi = gdvr::square_to_cosine_hemisphere({vx, vy});
  const float pdf = gdvr::square_to_cosine_hemisphere_pdf(wi);
  if (!(pdf > 0.0f)) {
    st->alive = false;
    return;
  }
  st->throughput *= albedo;  // f cos / pdf
  const gdvr::Ray next = si.spawn_ray(si.sh_frame.to_world(wi));
  // Russian roulette.
  const float throughput_max = gdvr::max_component(st->throughput);
  if (st->depth + 1 >= kRrDepth) {
    const float q = gdvr::russian_roulette_survival(throughput_max, 1.0f);
    if (st->rng.next_float() >= q) {
      st->alive = false;
      return;
    }
    st->throughput *= 1.0f / q;
  }
  st->next_o = next.o;
  st->next_d = next.d;
  st->depth += 1;
}

// ------------------------------------------------------------------ SIMD form
// The same steps on kLanes paths at once, branches turned into lane masks.
typedef float vf __attribute__((vector_size(4 * kLanes)));
typedef double vd __attribute__((vector_size(8 * kLanes)));
typedef int32_t vi __attribute__((vector_size(4 * kLanes)));
typedef int64_t vi64 __attribute__((vector_size(8 * kLanes)));
typedef uint32_t vu __attribute__((vector_size(4 * kLanes)));
typedef uint64_t vu64 __attribute__((vector_size(8 * kLanes)));

inline vf splat(float x) { return vf{} + x; }
inline vf vsqrt(vf x) {
  vf r;
  for (int i = 0; i < kLanes; ++i) r[i] = __builtin_sqrtf(x[i]);
  return r;
}
inline vf safe_vsqrt(vf x) { return vsqrt(0.0f < x ? x : splat(0.0f)); }  // std::sqrt(std::max(0.0f, x))
inline vf vabs(vf x) { return (vf)((vu)x & 0x7fffffffu); }
inline vf vmax(vf a, vf b) { return a < b ? b : a; }  // std::max(a, b)
inline vf vmin(vf a, vf b) { return b < a ? b : a; }  // std::min(a, b)
inline vf vsel(vi m, vf a, vf b) { return m ? a : b; }
inline vi vsel(vi m, vi a, vi b) { return m ? a : b; }

#if defined(RECORDS) && defined(__AVX2__) && LANES == 8
constexpr bool kRecords = true;
// Eight records of 16 floats, as 16 vectors of 8 lanes (two 8 x 8 transposes).
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
  __m256 f[16];  // field k of the eight records
};
inline void load_records(const TriangleRecord* records, const int32_t* index, RecordLanes* out) {
  for (int i = 0; i < 8; ++i) {
    const float* rec = &records[index[i]].p0.x;
    out->f[i] = _mm256_load_ps(rec);
    out->f[8 + i] = _mm256_load_ps(rec + 8);
  }
  transpose8(out->f);
  transpose8(out->f + 8);
}
#else
constexpr bool kRecords = false;
#endif

// base[idx[i]] in every lane: the hardware gather where the ISA has one
// (AVX2, AVX-512), else lane by lane.
inline vf gather(const float* base, vi idx) {
#if defined(__AVX512F__) && LANES == 16
  return (vf)_mm512_mask_i32gather_ps(_mm512_setzero_ps(), 0xffff, (__m512i)idx, base, 4);
#elif defined(__AVX2__) && LANES == 8
  return (vf)_mm256_i32gather_ps(base, (__m256i)idx, 4);
#elif defined(__AVX2__) && LANES == 4
  return (vf)_mm_i32gather_ps(base, (__m128i)idx, 4);
#else
  vf r;
  for (int i = 0; i < kLanes; ++i) r[i] = base[idx[i]];
  return r;
#endif
}
inline vi gather(const int32_t* base, vi idx) {
#if defined(__AVX512F__) && LANES == 16
  return (vi)_mm512_mask_i32gather_epi32(_mm512_setzero_si512(), 0xffff, (__m512i)idx, base, 4);
#elif defined(__AVX2__) && LANES == 8
  return (vi)_mm256_i32gather_epi32(base, (__m256i)idx, 4);
#elif defined(__AVX2__) && LANES == 4
  return (vi)_mm_i32gather_epi32(base, (__m128i)idx, 4);
#else
  vi r;
  for (int i = 0; i < kLanes; ++i) r[i] = base[idx[i]];
  return r;
#endif
}

struct VV3 {
  vf x, y, z;
};
// Element `idx` of an array of three-float records (Vec3f, Rgb).
template <class T>
inline VV3 gather3(const T* records, vi idx) {
  static_assert(sizeof(T) == 3 * sizeof(float));
  const float* base = reinterpret_cast<const float*>(records);
  const vi at = idx * 3;
  return {gather(base, at), gather(base + 1, at), gather(base + 2, at)};
}
inline VV3 operator+(VV3 a, VV3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline VV3 operator-(VV3 a, VV3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline VV3 operator-(VV3 a) { return {-a.x, -a.y, -a.z}; }
inline VV3 operator*(VV3 a, vf s) { return {a.x * s, a.y * s, a.z * s}; }
inline VV3 operator*(VV3 a, VV3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline vf vdot(VV3 a, VV3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline VV3 vsel3(vi m, VV3 a, VV3 b) { return {vsel(m, a.x, b.x), vsel(m, a.y, b.y), vsel(m, a.z, b.z)}; }
inline VV3 splat3(Rgb c) { return {splat(c.r), splat(c.g), splat(c.b)}; }
// Frame::to_local and to_world, component by component as frame.h writes them.
inline VV3 to_world(VV3 s, VV3 t, VV3 n, vf x, vf y, vf z) { return s * x + t * y + n * z; }

struct VPcg32 {
  vu64 state, inc;
  vu next_u32() {
    const vu64 old = state;
    state = old * 6364136223846793005ULL + inc;
    const vu xorshifted = __builtin_convertvector(((old >> 18u) ^ old) >> 27u, vu);
    const vu rot = __builtin_convertvector(old >> 59u, vu);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
  }
  // Advances only the lanes in m (paths that draw this number).
  vf next_float(vi m) {
    const vu64 before = state;
    const vf u = __builtin_convertvector((vi)(next_u32() >> 8u), vf) * 0x1p-24f;
    const vu64 m64 = __builtin_convertvector(m, vu64);  // 0 or all ones (sign-extended)
    state = (state & m64) | (before & ~m64);
    return u;
  }
};

// SurfaceInteraction::offset_p.
inline VV3 voffset_p(VV3 p, vf offset_floor, VV3 n, VV3 d) {
  vf mag = (offset_floor + vmax(vabs(p.x), vmax(vabs(p.y), vabs(p.z)))) * gdvr::kRayEpsilon;
  mag = vsel(vdot(n, d) < 0, -mag, mag);
  return p + n * mag;
}

// What kLanes paths' vertices read, and what they write.
struct VIn {
  vi alive;
  VPcg32 rng;
  vi prim;
  vf b1, b2;
  VV3 ray_d, throughput;
  vi depth;
};
struct VOut {
  vi alive_before, connect, alive;
  VV3 contribution, shadow_o, shadow_d, throughput, next_o, next_d;
  vf shadow_tmax;
  vi depth;
  vu64 rng_state;
};

VOut simd_vertex_math(const Light& light, const Mesh& mesh, VIn in) {
  VOut out;
  out.alive_before = in.alive != 0;
  vi alive = out.alive_before;
  VPcg32 rng = in.rng;
  VV3 throughput = in.throughput;

  // The hit: the triangle's corners, normal, offset floor and reflectance,
  // gathered field by field or (RECORDS) loaded as whole records.
  VV3 c0, c1, c2, n, albedo;
  vf offset_floor;
#if defined(RECORDS) && defined(__AVX2__) && LANES == 8
  {
    int32_t prims[8];
    for (int i = 0; i < 8; ++i) prims[i] = in.prim[i];
    RecordLanes r;
    load_records(mesh.records.data(), prims, &r);
    auto f = [&r](int k) { return (vf)r.f[k]; };
    c0 = {f(0), f(1), f(2)}, c1 = {f(3), f(4), f(5)}, c2 = {f(6), f(7), f(8)}, n = {f(9), f(10), f(11)};
    albedo = {f(12), f(13), f(14)}, offset_floor = f(15);
  }
#else
  const int32_t* indices = reinterpret_cast<const int32_t*>(mesh.indices.data());
  const vi corner = in.prim * 3;
  c0 = gather3(mesh.positions.data(), gather(indices, corner));
  c1 = gather3(mesh.positions.data(), gather(indices, corner + 1));
  c2 = gather3(mesh.positions.data(), gather(indices, corner + 2));
  n = gather3(mesh.face_normals.data(), in.prim);
  albedo = gather3(mesh.albedo.data(), in.prim);
  offset_floor = gather(mesh.offset_floors.data(), in.prim);
#endif
  const VV3 p = c0 * (1.0f - in.b1 - in.b2) + c1 * in.b1 + c2 * in.b2;

  // Frame(n), Duff et al.
  const vf sign = (vf)(((vu)n.z & 0x80000000u) | 0x3f800000u);  // copysign(1, n.z)
  const vf a = -1.0f / (sign + n.z);
  const vf b = n.x * n.y * a;
  const VV3 s{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
  const VV3 t{b, sign + n.y * n.y * a, -n.y};
  alive &= vdot(-in.ray_d, n) > 0.0f;

  // Next-event estimation.
  (void)rng.next_float(alive);
  const vf ux = rng.next_float(alive), uy = rng.next_float(alive);
  // Distribution1D::sample over two equal weights: floor(u n) in double.
  const vd scaled = __builtin_convertvector(ux, vd) * 2.0;
  vi64 ti = __builtin_convertvector(scaled, vi64);
  ti = ti < 1 ? ti : 1;
  vd rest = scaled - __builtin_convertvector(ti, vd);
  rest = rest < 0.0 ? 0.0 : (double(0x1.fffffep-1f) < rest ? double(0x1.fffffep-1f) : rest);
  const vf u_tri = __builtin_convertvector(rest, vf);
  // The light's triangle, gathered (a general light list is a gather), or
  // (RECORDS) loaded as whole records.
  const vi light_tri = __builtin_convertvector(ti, vi);
#if defined(RECORDS) && defined(__AVX2__) && LANES == 8
  int32_t tris[8];
  for (int i = 0; i < 8; ++i) tris[i] = light_tri[i];
  RecordLanes lr;
  load_records(light.records, tris, &lr);
  auto lf = [&lr](int k) { return (vf)lr.f[k]; };
  const VV3 p0{lf(0), lf(1), lf(2)}, p1{lf(3), lf(4), lf(5)}, p2{lf(6), lf(7), lf(8)}, tn{lf(9), lf(10), lf(11)};
#else
  const VV3 p0 = gather3(light.p0, light_tri), p1 = gather3(light.p1, light_tri), p2 = gather3(light.p2, light_tri);
  const VV3 tn = gather3(light.n, light_tri);
#endif
  const vf tt = safe_vsqrt(1.0f - u_tri);
  const vf b1 = 1.0f - tt, b2 = tt * uy;
  const VV3 lp = p0 * (1.0f - b1 - b2) + p1 * b1 + p2 * b2;
  const VV3 d = lp - p;
  const vf dist2 = vdot(d, d);
  const vf dist = vsqrt(dist2);
  const vf abs_dn = vabs(vdot(d, tn));
  const vf pdf_area = vsel(abs_dn > 0, dist2 * (dist / (light.area * abs_dn)), splat(0.0f));
  const vi finite = vabs(pdf_area) < std::numeric_limits<float>::infinity();
  const VV3 dir = d * (1.0f / dist);
  const vf pdf = pdf_area * (1.0f / 1.0f);
  const vf wl_z = vdot(dir, n);
  out.connect = alive & (dist > 0) & (pdf_area > 0) & finite & (vdot(tn, dir) < 0) & (wl_z > 0.0f);
  const VV3 weight = splat3(light.radiance) * (1.0f / pdf);
  const vf bsdf_pdf = gdvr::kInvPi * wl_z;
  const VV3 f = albedo * bsdf_pdf;
  const vf pa = pdf * pdf, pb = bsdf_pdf * bsdf_pdf;
  // mis_power: 0 where pa underflows, 1 where it overflows.
  const vf w = vsel(pa > 0, vsel(vabs(pa) < std::numeric_limits<float>::infinity(), pa / (pa + pb), splat(1.0f)),
                    splat(0.0f));
  out.contribution = throughput * f * weight * w;
  out.shadow_o = voffset_p(p, offset_floor, n, dir);
  out.shadow_d = dir;
  out.shadow_tmax = dist * (1.0f - gdvr::kShadowEpsilon);

  // The bounce: square_to_cosine_hemisphere through the concentric disk.
  (void)rng.next_float(alive);
  const vf vx = rng.next_float(alive), vy = rng.next_float(alive);
  const vf x = 2.0f * vx - 1.0f, y = 2.0f * vy - 1.0f;
  const vi origin = (x == 0) & (y == 0);
  const vi x_major = vabs(x) > vabs(y);
  const vf r = vsel(x_major, x, y);
  const vf arg = (gdvr::kPi / 4.0f) * (vsel(x_major, y, x) / vsel(origin, splat(1.0f), r));
  const vf x2 = arg * arg;  // sincos_eighth_turn
  const vf sn = arg * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f)))));
  const vf cs =
      1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f + x2 * (-1.0f / 3628800.0f)))));
  const vf dx = vsel(origin, splat(0.0f), vsel(x_major, r * cs, r * sn));
  const vf dy = vsel(origin, splat(0.0f), vsel(x_major, r * sn, r * cs));
  const vf z = safe_vsqrt(1.0f - dx * dx - dy * dy);
  alive &= gdvr::kInvPi * z > 0.0f;
  const VV3 wi = to_world(s, t, n, dx, dy, z);
  throughput = vsel3(alive, throughput * albedo, throughput);
  // Russian roulette.
  const vf throughput_max = vmax(throughput.x, vmax(throughput.y, throughput.z));
  const vi rr = alive & (in.depth + 1 >= kRrDepth);
  const vf q = vmin(throughput_max * 1.0f * 1.0f, splat(1.0f));
  const vf u = rng.next_float(rr);
  alive &= ~rr | (u < q);
  out.throughput = vsel3(rr & alive, throughput * (1.0f / q), throughput);
  out.next_o = voffset_p(p, offset_floor, n, wi);
  out.next_d = wi;
  out.depth = in.depth + (alive & 1);
  out.alive = alive;
  out.rng_state = rng.state;
  return out;
}

// State as struct of arrays: whole vectors in and out.
struct SoaPaths {
  alignas(64) uint64_t rng_state[kPaths], rng_inc[kPaths];
  alignas(64) int32_t prim[kPaths];
  alignas(64) float b1[kPaths], b2[kPaths], ray_d[3][kPaths], throughput[3][kPaths];
  alignas(64) int32_t depth[kPaths], alive[kPaths];
  alignas(64) float shadow_o[3][kPaths], shadow_d[3][kPaths], contribution[3][kPaths], next_o[3][kPaths],
      next_d[3][kPaths], shadow_tmax[kPaths];
  alignas(64) int32_t shadow_pending[kPaths];
};

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
inline VV3 load3(const float (*a)[kPaths], int k) { return {load<vf>(&a[0][k]), load<vf>(&a[1][k]), load<vf>(&a[2][k])}; }
// Stores only the lanes in m (the scalar form leaves the others as they were).
inline void store3(float (*a)[kPaths], int k, VV3 v, vi m) {
  store(&a[0][k], vsel(m, v.x, load<vf>(&a[0][k])));
  store(&a[1][k], vsel(m, v.y, load<vf>(&a[1][k])));
  store(&a[2][k], vsel(m, v.z, load<vf>(&a[2][k])));
}

void simd_vertices(const Light& light, const Mesh& mesh, SoaPaths* sp, int k) {
  VIn in{load<vi>(&sp->alive[k]), VPcg32{load<vu64>(&sp->rng_state[k]), load<vu64>(&sp->rng_inc[k])},
         load<vi>(&sp->prim[k]), load<vf>(&sp->b1[k]), load<vf>(&sp->b2[k]), load3(sp->ray_d, k),
         load3(sp->throughput, k), load<vi>(&sp->depth[k])};
  const VOut o = simd_vertex_math(light, mesh, in);
  store3(sp->contribution, k, o.contribution, o.connect);
  store3(sp->shadow_o, k, o.shadow_o, o.connect);
  store3(sp->shadow_d, k, o.shadow_d, o.connect);
  store(&sp->shadow_tmax[k], vsel(o.connect, o.shadow_tmax, load<vf>(&sp->shadow_tmax[k])));
  store(&sp->shadow_pending[k], vsel(o.alive_before, (vi)(o.connect & 1), load<vi>(&sp->shadow_pending[k])));
  store3(sp->throughput, k, o.throughput, o.alive_before);
  store3(sp->next_o, k, o.next_o, o.alive);
  store3(sp->next_d, k, o.next_d, o.alive);
  store(&sp->depth[k], o.depth);
  store(&sp->alive[k], o.alive & 1);
  store(&sp->rng_state[k], o.rng_state);
}

// State as the path structs the renderer has now: gathered into vectors and
// scattered back lane by lane.
inline void gather3(VV3* v, int i, float x, float y, float z) { v->x[i] = x, v->y[i] = y, v->z[i] = z; }
inline Vec3f lane_vec(const VV3& v, int i) { return {v.x[i], v.y[i], v.z[i]}; }
inline Rgb lane_rgb(const VV3& v, int i) { return {v.x[i], v.y[i], v.z[i]}; }
void simd_vertices_aos(const Light& light, const Mesh& mesh, ScalarPath* paths) {
  VIn in;
  for (int i = 0; i < kLanes; ++i) {
    const ScalarPath& st = paths[i];
    uint64_t words[2];
    pcg_words(st.rng, words);
    in.alive[i] = st.alive;
    in.rng.state[i] = words[0], in.rng.inc[i] = words[1];
    in.prim[i] = int32_t(st.prim), in.b1[i] = st.b1, in.b2[i] = st.b2;
    gather3(&in.ray_d, i, st.ray_d.x, st.ray_d.y, st.ray_d.z);
    gather3(&in.throughput, i, st.throughput.r, st.throughput.g, st.throughput.b);
    in.depth[i] = st.depth;
  }
  const VOut o = simd_vertex_math(light, mesh, in);
  for (int i = 0; i < kLanes; ++i) {
    ScalarPath& st = paths[i];
    if (!o.alive_before[i]) continue;
    st.shadow_pending = o.connect[i] != 0;
    if (o.connect[i]) {
      st.contribution = lane_rgb(o.contribution, i), st.shadow_o = lane_vec(o.shadow_o, i);
      st.shadow_d = lane_vec(o.shadow_d, i), st.shadow_tmax = o.shadow_tmax[i];
    }
    st.throughput = lane_rgb(o.throughput, i);
    st.alive = o.alive[i] != 0;
    if (st.alive) st.next_o = lane_vec(o.next_o, i), st.next_d = lane_vec(o.next_d, i);
    st.depth = o.depth[i];
    uint64_t words[2] = {o.rng_state[i], uint64_t(in.rng.inc[i])};
    set_pcg_words(&st.rng, words);
  }
}

// ------------------------------------------------------------------- harness
Light cbox_light() {
  // The quad light of a Cornell box, facing down.
  const Vec3f a{-0.24f, 1.98f, -0.22f}, b{0.23f, 1.98f, -0.22f}, c{0.23f, 1.98f, 0.16f}, d{-0.24f, 1.98f, 0.16f};
  Light l;
  l.p0[0] = a, l.p1[0] = b, l.p2[0] = c;
  l.p0[1] = a, l.p1[1] = c, l.p2[1] = d;
  l.n[0] = l.n[1] = Vec3f(0, -1, 0);
  l.area = (b.x - a.x) * (c.z - b.z);
  l.radiance = Rgb(17.0f, 12.0f, 4.0f);
  for (int t = 0; t < 2; ++t) l.records[t] = {l.p0[t], l.p1[t], l.p2[t], l.n[t], Rgb(0.0f), 0.0f};
  return l;
}

// The five walls of a 2-unit box, each a kGrid x kGrid grid of quads (two
// triangles each), facing inwards; the floor, ceiling and back wall white,
// the sides red and green.
Mesh cbox_walls() {
  constexpr int kGrid = 4;
  const Rgb white{0.58f, 0.57f, 0.55f}, red{0.63f, 0.065f, 0.05f}, green{0.14f, 0.45f, 0.091f};
  struct Wall {
    Vec3f origin, du, dv;  // du x dv faces inwards
    Rgb albedo;
  };
  const Wall walls[5] = {{{-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, white},   // floor, +y
                         {{-1, 2, -1}, {2, 0, 0}, {0, 0, 2}, white},   // ceiling, -y
                         {{-1, 0, -1}, {2, 0, 0}, {0, 2, 0}, white},   // back, +z
                         {{-1, 0, -1}, {0, 2, 0}, {0, 0, 2}, red},     // left, +x
                         {{1, 0, -1}, {0, 0, 2}, {0, 2, 0}, green}};   // right, -x
  Mesh m;
  for (const Wall& w : walls) {
    const uint32_t base = uint32_t(m.positions.size());
    for (int j = 0; j <= kGrid; ++j)
      for (int i = 0; i <= kGrid; ++i)
        m.positions.push_back(w.origin + w.du * (float(i) / kGrid) + w.dv * (float(j) / kGrid));
    for (int j = 0; j < kGrid; ++j)
      for (int i = 0; i < kGrid; ++i) {
        const uint32_t v00 = base + uint32_t(j * (kGrid + 1) + i), v10 = v00 + 1, v01 = v00 + kGrid + 1,
                       v11 = v01 + 1;
        const uint32_t tris[2][3] = {{v00, v10, v11}, {v00, v11, v01}};
        for (const auto& t : tris) {
          m.indices.insert(m.indices.end(), {t[0], t[1], t[2]});
          const Vec3f p0 = m.positions[t[0]], p1 = m.positions[t[1]], p2 = m.positions[t[2]];
          m.face_normals.push_back(gdvr::normalize(gdvr::cross(p1 - p0, p2 - p0)));
          m.offset_floors.push_back(std::min(
              1.0f, std::max(gdvr::max_abs_component(p0),
                             std::max(gdvr::max_abs_component(p1), gdvr::max_abs_component(p2)))));
          m.albedo.push_back(w.albedo);
          m.records.push_back({p0, p1, p2, m.face_normals.back(), w.albedo, m.offset_floors.back()});
        }
      }
  }
  return m;
}

// Hits spread over the walls, reached from random points inside the box.
std::vector<ScalarPath> make_paths(const Mesh& mesh, int count, uint64_t seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<ScalarPath> paths(static_cast<size_t>(count));
  const uint32_t triangles = uint32_t(mesh.face_normals.size());
  for (ScalarPath& st : paths) {
    st.prim = std::min(triangles - 1, uint32_t(u(gen) * float(triangles)));
    float b1 = u(gen), b2 = u(gen);
    if (b1 + b2 > 1.0f) b1 = 1.0f - b1, b2 = 1.0f - b2;
    st.b1 = b1, st.b2 = b2;
    const uint32_t* ix = &mesh.indices[3 * st.prim];
    const Vec3f p = mesh.positions[ix[0]] * (1.0f - b1 - b2) + mesh.positions[ix[1]] * b1 + mesh.positions[ix[2]] * b2;
    const Vec3f from{u(gen) * 1.6f - 0.8f, u(gen) * 1.6f + 0.2f, u(gen) * 1.6f - 0.8f};
    st.rng = gdvr::Pcg32(gen(), gen());
    st.ray_d = gdvr::normalize(p - from);
    st.throughput = Rgb(u(gen), u(gen), u(gen));
    st.depth = int(u(gen) * 8);
    st.alive = true;
    st.shadow_o = st.shadow_d = st.next_o = st.next_d = Vec3f(0.0f);
    st.contribution = Rgb(0.0f);
    st.shadow_tmax = 0;
    st.shadow_pending = false;
  }
  return paths;
}

inline void put3(float (*a)[kPaths], int i, float x, float y, float z) { a[0][i] = x, a[1][i] = y, a[2][i] = z; }
void to_soa(const ScalarPath* in, SoaPaths* out) {
  for (int i = 0; i < kPaths; ++i) {
    const ScalarPath& st = in[i];
    uint64_t words[2];
    pcg_words(st.rng, words);
    out->rng_state[i] = words[0], out->rng_inc[i] = words[1];
    out->prim[i] = int32_t(st.prim), out->b1[i] = st.b1, out->b2[i] = st.b2;
    put3(out->ray_d, i, st.ray_d.x, st.ray_d.y, st.ray_d.z);
    put3(out->throughput, i, st.throughput.r, st.throughput.g, st.throughput.b);
    put3(out->shadow_o, i, 0, 0, 0), put3(out->shadow_d, i, 0, 0, 0), put3(out->contribution, i, 0, 0, 0);
    put3(out->next_o, i, 0, 0, 0), put3(out->next_d, i, 0, 0, 0);
    out->depth[i] = st.depth, out->alive[i] = st.alive, out->shadow_tmax[i] = st.shadow_tmax;
    out->shadow_pending[i] = st.shadow_pending;
  }
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same(float x, float y, float z, const float (*soa)[kPaths], int i) {
  return same_bits(x, soa[0][i]) && same_bits(y, soa[1][i]) && same_bits(z, soa[2][i]);
}
bool same(Vec3f v, const float (*soa)[kPaths], int i) { return same(v.x, v.y, v.z, soa, i); }
bool same(Rgb c, const float (*soa)[kPaths], int i) { return same(c.r, c.g, c.b, soa, i); }
bool same_path(const ScalarPath& x, const ScalarPath& y) {
  uint64_t wx[2], wy[2];
  pcg_words(x.rng, wx), pcg_words(y.rng, wy);
  auto eq = [](const auto& a, const auto& b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  return wx[0] == wy[0] && x.alive == y.alive && x.depth == y.depth && x.shadow_pending == y.shadow_pending &&
         eq(x.throughput, y.throughput) && eq(x.contribution, y.contribution) && eq(x.shadow_o, y.shadow_o) &&
         eq(x.shadow_d, y.shadow_d) && same_bits(x.shadow_tmax, y.shadow_tmax) && eq(x.next_o, y.next_o) &&
         eq(x.next_d, y.next_d);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main() {
  const Light light = cbox_light();
  const Mesh mesh = cbox_walls();
  constexpr int kBatches = 256, kBounces = 4, kRuns = 15;
  const std::vector<ScalarPath> initial = make_paths(mesh, kPaths * kBatches, 12345);
  std::vector<SoaPaths> soa_initial(kBatches);
  for (int bt = 0; bt < kBatches; ++bt) to_soa(&initial[size_t(bt) * kPaths], &soa_initial[size_t(bt)]);
  auto run_scalar = [&](std::vector<ScalarPath>* paths) {
    size_t vertices = 0;
    for (int bt = 0; bt < kBatches; ++bt)
      for (int bounce = 0; bounce < kBounces; ++bounce)
        for (int i = 0; i < kPaths; ++i) {
          ScalarPath& st = (*paths)[size_t(bt) * kPaths + size_t(i)];
          if (st.alive) scalar_vertex(light, mesh, &st), ++vertices;
        }
    return vertices;
  };
  auto run_soa = [&](std::vector<SoaPaths>* soa) {
    for (int bt = 0; bt < kBatches; ++bt)
      for (int bounce = 0; bounce < kBounces; ++bounce)
        for (int k = 0; k < kPaths; k += kLanes) simd_vertices(light, mesh, &(*soa)[size_t(bt)], k);
  };
  auto run_gathered = [&](std::vector<ScalarPath>* paths) {
    for (int bt = 0; bt < kBatches; ++bt)
      for (int bounce = 0; bounce < kBounces; ++bounce)
        for (int k = 0; k < kPaths; k += kLanes) simd_vertices_aos(light, mesh, &(*paths)[size_t(bt) * kPaths + size_t(k)]);
  };

  // Same bits: kBounces vertices of every path in all three forms (paths
  // stay where they are; the numbers and the throughput move on).
  std::vector<ScalarPath> scalar = initial, gathered = initial;
  std::vector<SoaPaths> soa = soa_initial;
  const size_t vertices = run_scalar(&scalar);
  run_soa(&soa);
  run_gathered(&gathered);
  size_t soa_mismatches = 0, gathered_mismatches = 0;
  for (size_t j = 0; j < scalar.size(); ++j) {
    const ScalarPath& st = scalar[j];
    const SoaPaths& sp = soa[j / kPaths];
    const int i = int(j % kPaths);
    const bool ok = st.alive == bool(sp.alive[i]) && st.depth == sp.depth[i] &&
                    st.shadow_pending == bool(sp.shadow_pending[i]) && same(st.throughput, sp.throughput, i) &&
                    same(st.contribution, sp.contribution, i) && same(st.shadow_o, sp.shadow_o, i) &&
                    same(st.shadow_d, sp.shadow_d, i) && same_bits(st.shadow_tmax, sp.shadow_tmax[i]) &&
                    same(st.next_o, sp.next_o, i) && same(st.next_d, sp.next_d, i);
    uint64_t words[2];
    pcg_words(st.rng, words);
    soa_mismatches += !ok || words[0] != sp.rng_state[i];
    gathered_mismatches += !same_path(st, gathered[j]);
  }
  std::printf("%s", kRecords ? "scene loads: one record per triangle, transposed\n" : "");
  std::printf("lanes %d, %zu vertices of %zu paths; paths that differ from the scalar form: %zu (struct of arrays), %zu (gathered)\n",
              kLanes, vertices, scalar.size(), soa_mismatches, gathered_mismatches);

  // Time: the three forms alternate within each run.
  std::vector<double> t_scalar, t_soa, t_gathered;
  auto ns_per_vertex = [&](auto t0, auto t1) {
    return std::chrono::duration<double, std::nano>(t1 - t0).count() / double(vertices);
  };
  for (int run = 0; run < kRuns; ++run) {
    scalar = initial, gathered = initial, soa = soa_initial;
    auto t0 = std::chrono::steady_clock::now();
    run_scalar(&scalar);
    auto t1 = std::chrono::steady_clock::now();
    run_soa(&soa);
    auto t2 = std::chrono::steady_clock::now();
    run_gathered(&gathered);
    auto t3 = std::chrono::steady_clock::now();
    t_scalar.push_back(ns_per_vertex(t0, t1));
    t_soa.push_back(ns_per_vertex(t1, t2));
    t_gathered.push_back(ns_per_vertex(t2, t3));
  }
  const double scalar_ns = median(t_scalar);
  std::printf("scalar                 %6.2f ns per vertex\n", scalar_ns);
  std::printf("simd, struct of arrays %6.2f ns per vertex (%.2fx)\n", median(t_soa), scalar_ns / median(t_soa));
  std::printf("simd, gathered structs %6.2f ns per vertex (%.2fx)   medians of %d runs\n", median(t_gathered),
              scalar_ns / median(t_gathered), kRuns);
  return soa_mismatches == 0 && gathered_mismatches == 0 ? 0 : 1;
}
