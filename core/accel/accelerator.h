// Ray-scene intersection, the one module that talks to Embree 3. Callers add
// geometry under their own integer ids (gdvr's shape indices) and get those
// ids back in hits; no Embree type leaves this module.
//
// Static geometry lives directly in the top-level scene (in world space).
// Geometry that animates is added as an instance of its own object-space scene,
// so a frame change only updates an instance transform and refits the top
// level instead of rebuilding every BVH.
#pragma once

#include <cstdint>
#include <memory>

#include "core/math/transform.h"
#include "core/math/vec.h"
#include "core/util/status.h"

namespace gdvr {

struct RayHit {
  float t = 0;
  int id = -1;         // the caller's geometry id
  uint32_t prim = 0;   // triangle index within the mesh (0 for spheres)
  float u = 0, v = 0;  // Embree barycentrics: p = (1-u-v) p0 + u p1 + v p2
};

class Accelerator {
 public:
  static Expected<std::unique_ptr<Accelerator>> create();
  ~Accelerator();
  Accelerator(const Accelerator&) = delete;
  Accelerator& operator=(const Accelerator&) = delete;

  // `instanced`: the mesh is in object space and placed by `to_world`, which
  // can change later with set_instance_transform. Otherwise it is in world space.
  Status add_mesh(int id, const Vec3f* positions, size_t vertex_count, const uint32_t* indices,
                  size_t triangle_count, bool instanced, const Transform& to_world);
  Status add_sphere(int id, Vec3f center, float radius, bool instanced, const Transform& to_world);
  Status set_instance_transform(int id, const Transform& to_world);
  // Builds or refits; must be called after adding geometry or moving instances.
  Status commit();

  // Closest hit with t in (tmin, tmax). Thread-safe after commit().
  bool intersect(Vec3f origin, Vec3f dir, float tmin, float tmax, RayHit* hit) const;
  // Any hit with t in (tmin, tmax); `instanced_only`: test only the geometry
  // added with instanced = true (Embree ray masks).
  bool occluded(Vec3f origin, Vec3f dir, float tmin, float tmax, bool instanced_only = false) const;

 private:
  struct Impl;
  explicit Accelerator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace gdvr
