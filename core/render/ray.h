// Rays and surface interactions shared by the integrators.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

#include "core/math/frame.h"
#include "core/math/vec.h"

namespace gdvr {

constexpr float kInfinity = std::numeric_limits<float>::infinity();
// Mitsuba's ray epsilons (float): offsets scale with the magnitude of the
// position. Mitsuba floors that magnitude at 1, which makes offsets of 1e-4
// in a scene 1e-4 across; gdvr floors it at the magnitude of the hit
// primitive instead (SurfaceInteraction::offset_floor), so scenes at 1e-4
// and at 1e5 scale both work and unit-scale scenes offset exactly as Mitsuba.
constexpr float kRayEpsilon = 8.940697e-05f;   // 1500 float ulps at 1
constexpr float kShadowEpsilon = kRayEpsilon * 10.0f;

// SurfaceInteraction::offset_floor of a hit on the triangle (p0, p1, p2).
inline float triangle_offset_floor(Vec3f p0, Vec3f p1, Vec3f p2) {
  return std::min(1.0f, std::max({max_abs_component(p0), max_abs_component(p1), max_abs_component(p2)}));
}

struct Ray {
  Vec3f o, d;
  float tmin = 0, tmax = kInfinity;
};

struct SurfaceInteraction {
  Vec3f p;          // world position
  float t = 0;      // ray distance
  Vec3f n;          // geometric normal (unit, world; flipped with flip_normals)
  Frame sh_frame;   // shading frame (z = interpolated shading normal)
  Vec2f uv;
  int shape = -1;
  uint32_t prim = 0;
  Vec3f wi;         // direction towards the ray origin, in the shading frame
  // min(1, largest coordinate magnitude of the hit primitive): the scale of
  // the floating-point error in p (set by FrameScene::intersect).
  float offset_floor = 1.0f;

  // Offset origin for a ray leaving in direction d (Mitsuba's offset_p).
  Vec3f offset_p(Vec3f d) const {
    float mag = (offset_floor + max_abs_component(p)) * kRayEpsilon;
    if (dot(n, d) < 0) mag = -mag;
    return p + n * mag;
  }
  Ray spawn_ray(Vec3f d) const { return Ray{offset_p(d), d, 0.0f, kInfinity}; }
  // A visibility ray to the surface point y, offset at both ends and aimed
  // from the offset origin to the offset target (pbrt-v4's SpawnRayTo). A ray
  // parallel to p -> y.p from the offset origin reaches y's plane early when it
  // arrives at an angle, and y's own triangle then occludes it.
  Ray spawn_ray_to(const SurfaceInteraction& y) const {
    const Vec3f to = y.p - p;
    const Vec3f o = offset_p(to), target = y.offset_p(-to);
    const Vec3f d = target - o;
    const float dist = length(d);
    return Ray{o, d * (1.0f / dist), 0.0f, dist * (1.0f - kShadowEpsilon)};
  }
};

}  // namespace gdvr
