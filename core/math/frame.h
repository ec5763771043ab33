// Orthonormal shading frame: local z is the normal. BSDFs work in this frame.
#pragma once

#include <cmath>

#include "core/math/vec.h"

namespace gdvr {

struct Frame {
  Vec3f s, t, n;

  Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
  // Branchless construction of Duff et al. 2017 ("Building an orthonormal basis, revisited").
  explicit Frame(Vec3f normal) : n(normal) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    s = Vec3f(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3f(b, sign + n.y * n.y * a, -n.y);
  }
  // The frame around unit `normal` whose s is `tangent` made orthogonal to it
  // (Gram-Schmidt), as Mitsuba 3 orients shading frames along dp/du, which
  // anisotropic BSDFs depend on; Frame(normal) where `tangent` is (nearly)
  // parallel to the normal or not finite.
  static Frame along_tangent(Vec3f normal, Vec3f tangent) {
    Vec3f s = tangent - normal * dot(normal, tangent);
    const float len2 = length_squared(s);
    if (!(len2 > 1e-12f * length_squared(tangent)) || !std::isfinite(len2)) return Frame(normal);
    Frame f;
    f.n = normal;
    f.s = s * (1.0f / std::sqrt(len2));
    f.t = cross(normal, f.s);
    return f;
  }

  Vec3f to_local(Vec3f v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3f to_world(Vec3f v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace gdvr
