#include "core/emitter/environment_emitter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/math/arctan.h"
#include "core/math/sampling.h"

namespace gdvr {
namespace {

// Mitsuba's lat-long convention (envmap.cpp): u = atan2(x, -z) / 2pi, v = acos(y) / pi.
Vec2f direction_to_uv(Vec3f d) {
  const float u = atan2_turns(d.x, -d.z);
  // u is in [-1/2, 1/2]: u - floor(u) without floor (a libm call or a long
  // inline sequence without SSE4.1).
  return {u < 0.0f ? u + 1.0f : u, acos_half_turns(d.y)};
}

Vec3f uv_to_direction(Vec2f uv, float* sin_theta) {
  const SinCos theta = sincos_turns(0.5f * uv.y), phi = sincos_turns(uv.x);
  *sin_theta = theta.sin;
  return {phi.sin * theta.sin, theta.cos, -phi.cos * theta.sin};
}

// The four texels of a bilinear lookup, as Mitsuba 3's envmap: texel (i, j)
// at u = (i + 1/2) / width, periodic in u (the lookup between the last and the
// first column wraps), and at v = j / (height - 1). Texels at u = i / width
// (the convention of earlier Mitsuba versions) shifted the whole map by half a
// texel: matpreview rendered 0.3 % brighter than Mitsuba 3.9.
struct BilinearTexels {
  int x0, x1, y0, y1;
  float fx, fy;
};

BilinearTexels envmap_texels(const Image& img, Vec2f uv) {
  int w = img.width(), h = img.height();
  // x counts from the centre of the column before column 0 (the last one,
  // periodically): x in [1/2, w + 1/2] for u in [0, 1], so truncation is
  // floor (std::floor is a libm call without SSE4.1; this runs for every
  // environment lookup and prefetch).
  float x = std::max(0.0f, uv.x) * float(w) + 0.5f, y = std::max(0.0f, uv.y) * float(h - 1);  // NaN -> 0
  int xb = std::min(int(x), w), y0 = std::min(int(y), h - 1);
  float fx = std::clamp(x - float(xb), 0.0f, 1.0f), fy = std::clamp(y - float(y0), 0.0f, 1.0f);
  // Columns xb - 1 and xb, periodic: xb ∈ [0, w] (compares, not a division).
  int x0 = xb - 1, x1 = xb;
  if (x0 < 0) x0 += w;
  if (x1 >= w) x1 -= w;
  return {x0, x1, y0, std::min(y0 + 1, h - 1), fx, fy};
}

Rgb envmap_lookup(const Image& img, Vec2f uv) {
  const BilinearTexels t = envmap_texels(img, uv);
  return (img.rgb(t.x0, t.y0) * (1 - t.fx) + img.rgb(t.x1, t.y0) * t.fx) * (1 - t.fy) +
         (img.rgb(t.x0, t.y1) * (1 - t.fx) + img.rgb(t.x1, t.y1) * t.fx) * t.fy;
}

// Solid-angle density of an envmap sample at `local` (the envmap's frame), uv
// its texture position; without emitter selection.
float envmap_direction_pdf(const EnvmapTables& env, Vec3f local, Vec2f uv) {
  const float sin_theta = std::sqrt(std::max(local.x * local.x + local.z * local.z, 1e-14f));
  return env.distribution.pdf(uv) / (2.0f * kPi * kPi * sin_theta);
}

}  // namespace

// The piecewise-constant density that environment samples are drawn from:
// per cell of a grid finer than the texels (the lookup is bilinear between
// texel centres, so coarse cells leave L / pdf varying by up to 2x within a
// cell around a small bright feature: 1.6-1.8x Mitsuba's variance, whose
// sampling follows the bilinear lookup), the cell's luminance (its centre
// and corners, so that no cell where the map is not black gets zero weight)
// times sin(theta). 4 x 4 cells a texel matched Mitsuba's variance on the
// generated scenes; maps with more than 256K texels get fewer, which keeps the
// tables under 4M cells (their texels are small already).
Distribution2D envmap_distribution(const Image& img) {
  int k = 4;
  while (k > 1 && size_t(k) * k * size_t(img.width()) * size_t(img.height()) > (size_t(1) << 22)) k /= 2;
  const int w = k * img.width(), h = k * img.height();
  std::vector<float> weights(size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    const float sin_theta = std::sin(kPi * (float(y) + 0.5f) / float(h));
    const float v0 = float(y) / float(h), v1 = float(y + 1) / float(h);
    for (int x = 0; x < w; ++x) {
      const float u0 = float(x) / float(w), u1 = float(x + 1) / float(w);
      const float centre = luminance(envmap_lookup(img, {0.5f * (u0 + u1), 0.5f * (v0 + v1)}));
      const float corners = luminance(envmap_lookup(img, {u0, v0})) + luminance(envmap_lookup(img, {u1, v0})) +
                            luminance(envmap_lookup(img, {u0, v1})) + luminance(envmap_lookup(img, {u1, v1}));
      const float lum = std::max(0.0f, 0.5f * centre + 0.125f * corners);
      weights[size_t(y) * w + x] = std::isfinite(lum) ? lum * sin_theta : 0.0f;
    }
  }
  return Distribution2D(weights, w, h);
}

EmitterSample sample_constant_emitter(const Emitter& em, Vec2f u, float select_pdf, EmitterSample es) {
  es.d = square_to_uniform_sphere(u);
  es.dist = std::numeric_limits<float>::infinity();
  es.pdf = kInvFourPi * select_pdf;
  es.weight = em.radiance / es.pdf;
  return es;
}

EmitterSample sample_envmap_emitter(const Emitter& em, const EnvmapTables& env, Vec2f u, float select_pdf,
                                    EmitterSample es) {
  if (env.distribution.empty()) return es;
  float pdf_uv;
  Vec2f uv = env.distribution.sample(u, &pdf_uv);
  float sin_theta;
  Vec3f local = uv_to_direction(uv, &sin_theta);
  if (!(sin_theta > 1e-7f) || !(pdf_uv > 0)) return es;
  es.d = normalize(em.to_world.vector(local));
  es.dist = std::numeric_limits<float>::infinity();
  es.pdf = pdf_uv / (2.0f * kPi * kPi * sin_theta) * select_pdf;
  // The radiance at the sampled uv itself (no round trip through the
  // direction: two inverse trigonometric functions fewer).
  es.weight = envmap_lookup(*em.envmap, uv) * em.scale / es.pdf;
  return es;
}

Rgb eval_envmap(const Emitter& em, const EnvmapTables& env, Vec3f d) {
  Vec3f local = normalize(env.to_local.vector(d));
  return envmap_lookup(*em.envmap, direction_to_uv(local)) * em.scale;
}

float envmap_pdf(const EnvmapTables& env, Vec3f d) {
  const Vec3f local = normalize(env.to_local.vector(d));
  return envmap_direction_pdf(env, local, direction_to_uv(local));
}

EnvmapLookup envmap_along(const Emitter& em, const EnvmapTables& env, Vec3f d) {
  EnvmapLookup out;
  const Vec3f local = normalize(env.to_local.vector(d));
  const Vec2f uv = direction_to_uv(local);
  out.radiance = envmap_lookup(*em.envmap, uv) * em.scale;
  out.pdf = envmap_direction_pdf(env, local, uv);
  return out;
}

void prefetch_envmap_sample(const EnvmapTables& env, Vec2f u) {
  const Vec2f uv = env.distribution.prefetch_sample(u);
  const BilinearTexels t = envmap_texels(*env.image, uv);
  env.image->prefetch_rgb(t.x0, t.y0);
  env.image->prefetch_rgb(t.x0, t.y1);
}

}  // namespace gdvr
