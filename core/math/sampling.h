// Warps from the unit square to directions and surfaces, with their pdfs.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math/sincos.h"
#include "core/math/vec.h"

namespace gdvr {

// Shirley and Chiu's concentric map (Mitsuba's warp.h): the angle within each
// octant is pi/4 times a ratio, so its sine and cosine need no range reduction.
inline Vec2f square_to_uniform_disk_concentric(Vec2f u) {
  const float x = 2.0f * u.x - 1.0f, y = 2.0f * u.y - 1.0f;
  if (x == 0 && y == 0) return {0, 0};
  const bool x_major = std::abs(x) > std::abs(y);
  const float r = x_major ? x : y;
  // phi = a where x dominates, pi/2 - a where y does.
  const SinCos a = sincos_eighth_turn((kPi / 4.0f) * ((x_major ? y : x) / r));
  return x_major ? Vec2f(r * a.cos, r * a.sin) : Vec2f(r * a.sin, r * a.cos);
}

inline Vec3f square_to_cosine_hemisphere(Vec2f u) {
  Vec2f d = square_to_uniform_disk_concentric(u);
  float z = safe_sqrt(1.0f - d.x * d.x - d.y * d.y);
  return {d.x, d.y, z};
}
inline float square_to_cosine_hemisphere_pdf(Vec3f v) { return kInvPi * v.z; }

inline Vec3f square_to_uniform_sphere(Vec2f u) {
  float z = 1.0f - 2.0f * u.y;
  float r = safe_sqrt(1.0f - z * z);
  const SinCos phi = sincos_turns(u.x);
  return {r * phi.cos, r * phi.sin, z};
}

// Cones are described by 1 - cos(half-angle), not by the cosine: for a light
// that subtends 1e-4 rad, cos rounds to 1 in float and 1 - cos loses every
// digit, which biased small sphere lights (issue 6, docs/stability.md).

// 1 - cos(alpha) from sin^2(alpha) without cancellation: sin^2 / (1 + cos).
inline double cone_one_minus_cos_from_sin2(double sin2_alpha) {
  double s2 = std::min(sin2_alpha, 1.0);
  return s2 / (1.0 + std::sqrt(1.0 - s2));
}

// Solid-angle pdf of a uniform direction in the cone a sphere of squared
// radius r2 subtends from squared distance dist2 > r2 to its centre:
// 1 / (2 pi (1 - cos alpha)) with
// 1 - cos alpha = s / (1 + sqrt(1 - s)), s = r2 / dist2, multiplied out so that
// one sqrt and one division remain (three divisions before: they shared the
// divider with the sample's own and were 2-3 % of PT on veach-mis). Double:
// r2 of a 1e-20 radius stays representable, and no cancellation enters.
inline float sphere_cone_pdf(double dist2, double r2) {
  return float((dist2 + std::sqrt(dist2 * std::max(0.0, dist2 - r2))) / (2.0 * kPi * r2));
}

// Where on a sphere the direction at angle theta inside the cone it subtends
// lands, as the angle c at the centre between the reference point and that
// point: cos c = sin^2 theta / sin alpha + cos theta sqrt(1 - sin^2 theta /
// sin^2 alpha) (pbrt-v4), with 1 - cos theta = u (1 - cos alpha). sin c from
// cos c cancels where c is small; written in 1 - cos c, with x = sin^2 theta /
// sin^2 alpha,
//   1 - cos c = (sin^2 theta + x cos^2 theta) / (1 + cos theta sqrt(1 - x)) - x sin alpha,
// and the subtraction loses at most a factor 2 while sin alpha <= 1/4, so
// float suffices there (the lights of most scenes: 14 % of PT on veach-mis was
// this sample in double). Closer to larger spheres it runs in double.
// tests/core/math/sphere_cone_test.cpp checks both against long double.
struct SphereConePoint {
  float sin_c, cos_c;
};

inline SphereConePoint sphere_point_in_cone(float sin2_alpha, float u) {
  if (sin2_alpha <= 1.0f / 16.0f) {
    const float inv_one_plus_cos_alpha = 1.0f / (1.0f + std::sqrt(1.0f - sin2_alpha));
    const float one_minus_cos = u * (sin2_alpha * inv_one_plus_cos_alpha);  // of theta
    const float sin2 = one_minus_cos * (2.0f - one_minus_cos), cos_theta = 1.0f - one_minus_cos;
    // x = sin^2 theta / sin^2 alpha = u (1 + cos theta) / (1 + cos alpha), without dividing by sin^2 alpha.
    const float x = std::min(1.0f, u * (2.0f - one_minus_cos) * inv_one_plus_cos_alpha);
    const float one_minus_cos_c =
        std::max(0.0f, (sin2 + x * cos_theta * cos_theta) / (1.0f + cos_theta * std::sqrt(1.0f - x)) -
                           x * std::sqrt(sin2_alpha));
    return {std::sqrt(one_minus_cos_c * (2.0f - one_minus_cos_c)), 1.0f - one_minus_cos_c};
  }
  const double sin2_max = double(sin2_alpha), inv_sin_max = 1.0 / std::sqrt(sin2_max);
  const double one_minus_cos = double(u) * cone_one_minus_cos_from_sin2(sin2_max);
  const double sin2 = one_minus_cos * (2.0 - one_minus_cos), cos_theta = 1.0 - one_minus_cos;
  const double sin2_over_sin_max = sin2 * inv_sin_max;
  const double cos_c = sin2_over_sin_max + cos_theta * std::sqrt(std::max(0.0, 1.0 - sin2_over_sin_max * inv_sin_max));
  return {float(std::sqrt(std::max(0.0, 1.0 - cos_c * cos_c))), float(cos_c)};
}

// Barycentrics (b1, b2) uniform over a triangle (Heitz 2019 low-distortion map
// would also do; this is the classic square-root map).
inline Vec2f square_to_uniform_triangle(Vec2f u) {
  float t = safe_sqrt(1.0f - u.x);
  return {1.0f - t, t * u.y};
}

// Power heuristic with exponent 2 (Veach 1997), safe for zero and infinite pdfs.
inline float mis_power(float pdf_a, float pdf_b) {
  float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  if (!(a > 0)) return 0.0f;
  if (std::isinf(a)) return 1.0f;
  return a / (a + b);
}

}  // namespace gdvr
