// How every shape moves from one frame to another: M_s = to_world(t') ·
// to_world(t)⁻¹, identity for shapes whose transform does not change. The
// temporal path-space shift carries the base path's vertices with their
// shapes' motion (x'_k = M_s x_k), which preserves surface area for rigid
// motions (|J| = 1) and scales it by area_jacobian otherwise.
#pragma once

#include <vector>

#include "core/render/ray.h"
#include "core/scene/scene.h"

namespace gdvr {

class ShapeMotion {
 public:
  ShapeMotion() = default;
  // `from` and `to`: the same scene animated to the two frames' times.
  ShapeMotion(const Scene& from, const Scene& to);

  bool moves(int shape) const { return !identity_[size_t(shape)]; }
  // Same motion for both shapes (exact compare): a segment between them is
  // carried rigidly, its length and local directions unchanged.
  bool same(int a, int b) const;

  // The interaction at the other frame: position, geometric and shading
  // normals moved by M (shading frame rebuilt from the moved normal, and
  // tangent where the BSDF is anisotropic; uv,
  // shape, primitive kept). `wi` is left for the caller to set.
  SurfaceInteraction carry(const SurfaceInteraction& si) const;
  // dA'/dA at si: |det A| · |A⁻ᵀ n| for the linear part A of M (1 if rigid).
  float area_jacobian(const SurfaceInteraction& si) const;

 private:
  std::vector<Transform> motion_;
  std::vector<bool> identity_;
  std::vector<float> det_;
  std::vector<bool> tangent_;  // the shape's shading frame follows dp/du (anisotropic BSDF)
};

}  // namespace gdvr
