// An axis-aligned box in world space, empty until a point is added.
#pragma once

#include <limits>

#include "core/math/vec.h"

namespace gdvr {

struct Bounds3f {
  Vec3f lo = Vec3f(std::numeric_limits<float>::infinity());
  Vec3f hi = Vec3f(-std::numeric_limits<float>::infinity());

  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  void expand(Vec3f p) {
    lo = min(lo, p);
    hi = max(hi, p);
  }
  // Corner i in 0..7: bit 0 picks x, bit 1 y, bit 2 z.
  Vec3f corner(int i) const { return {(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z}; }
};

}  // namespace gdvr
