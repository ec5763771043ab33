// Warps from the unit square to directions and surfaces, with their pdfs.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math/vec.h"

namespace gdvr {

inline Vec2f square_to_uniform_disk_concentric(Vec2f u) {
  float x = 2.0f * u.x - 1.0f, y = 2.0f * u.y - 1.0f;
  if (x == 0 && y == 0) return {0, 0};
  float r, phi;
  if (std::abs(x) > std::abs(y)) {
    r = x;
    phi = (kPi / 4.0f) * (y / x);
  } else {
    r = y;
    phi = (kPi / 2.0f) - (kPi / 4.0f) * (x / y);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

inline Vec3f square_to_cosine_hemisphere(Vec2f u) {
  Vec2f d = square_to_uniform_disk_concentric(u);
  float z = safe_sqrt(1.0f - d.x * d.x - d.y * d.y);
  return {d.x, d.y, z};
}
inline float cosine_hemisphere_pdf(Vec3f v) { return v.z > 0 ? v.z * kInvPi : 0.0f; }

inline Vec3f square_to_uniform_sphere(Vec2f u) {
  float z = 1.0f - 2.0f * u.y;
  float r = safe_sqrt(1.0f - z * z);
  float phi = 2.0f * kPi * u.x;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Cones are described by 1 - cos(half-angle), not by the cosine: for a light
// that subtends 1e-4 rad, cos rounds to 1 in float and 1 - cos loses every
// digit, which biased small sphere lights (issue 6, docs/stability.md).

// 1 - cos(alpha) from sin^2(alpha) without cancellation: sin^2 / (1 + cos).
inline double cone_one_minus_cos_from_sin2(double sin2_alpha) {
  double s2 = std::min(sin2_alpha, 1.0);
  return s2 / (1.0 + std::sqrt(1.0 - s2));
}

// Solid-angle pdf of a uniform direction in a cone with 1 - cos(half-angle) = one_minus_cos_max.
inline float uniform_cone_pdf(double one_minus_cos_max) { return float(1.0 / (2.0 * kPi * one_minus_cos_max)); }

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
