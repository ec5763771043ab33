// Orthonormal shading frame: local z is the normal. BSDFs work in this frame.
#pragma once

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
  Vec3f to_local(Vec3f v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3f to_world(Vec3f v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace gdvr
