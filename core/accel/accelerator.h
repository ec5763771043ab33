// Ray-scene intersection, the one module that talks to Embree 3. Callers add
// geometry under their own integer ids (gdvr's shape indices) and get those
// ids back in hits; no Embree type leaves this module.
//
// Static geometry lives directly in the top-level scene (in world space).
// Geometry that animates is added as an instance of its own object-space scene,
// so a frame change only updates an instance transform and refits the top
// level instead of rebuilding every BVH. Geometry that emits light is also
// in a second top-level scene of emitters only, for closest-hit queries that
// look for emission alone (GeometrySet::kEmitters), and answers to a ray mask
// bit of its own so that a query can leave it out (GeometrySet::kNonEmitters).
#pragma once

#include <cstdint>
#include <limits>
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

// Up to kCapacity rays in the record layout Embree's stream queries read and
// answer in place (Embree's RTCRayHit: 80 bytes, checked field by field
// against <embree3/rtcore_ray.h> in accelerator.cpp). A caller writes its
// rays straight into the records and reads the answers from them: no staging
// copy on either side of the query (leaving out the copies cut 2.2 % of the
// path tracer's instructions on cbox; docs/renderer.md). The fields Embree
// only reads (time, mask, id, flags) are set once, here.
class RayStreamBuffer {
 public:
  static constexpr int kCapacity = 256;

  RayStreamBuffer() {
    for (Record& r : records_) {
      r.time = 0;
      r.mask = 0xFFFFFFFFu;
      r.id = 0;
      r.flags = 0;
    }
  }
  RayStreamBuffer(const RayStreamBuffer&) = delete;
  RayStreamBuffer& operator=(const RayStreamBuffer&) = delete;

  // Ray i of the next query, t in (tmin, tmax).
  void set(int i, const Vec3f& origin, const Vec3f& dir, float tmin, float tmax) {
    Record& r = records_[i];
    r.org_x = origin.x;
    r.org_y = origin.y;
    r.org_z = origin.z;
    r.tnear = tmin;
    r.dir_x = dir.x;
    r.dir_y = dir.y;
    r.dir_z = dir.z;
    r.tfar = tmax;
    r.geom_id = kInvalidId;
    r.inst_id = kInvalidId;
  }

  // After Accelerator::intersect_stream: whether ray i hit, and what.
  bool found(int i) const { return records_[i].geom_id != kInvalidId; }
  RayHit hit(int i) const {
    const Record& r = records_[i];
    RayHit h;
    h.t = r.tfar;
    h.id = int(r.inst_id != kInvalidId ? r.inst_id : r.geom_id);
    h.prim = r.prim_id;
    h.u = r.u;
    h.v = r.v;
    return h;
  }
  // After Accelerator::occluded_stream (Embree sets tfar to -inf on a hit).
  bool occluded(int i) const { return records_[i].tfar == -std::numeric_limits<float>::infinity(); }

  // The layout (RTCRayHit's); only the accelerator reads records whole.
  static constexpr uint32_t kInvalidId = 0xFFFFFFFFu;  // RTC_INVALID_GEOMETRY_ID
  struct alignas(16) Record {
    float org_x, org_y, org_z, tnear;
    float dir_x, dir_y, dir_z, time;
    float tfar;
    uint32_t mask, id, flags;
    float ng_x, ng_y, ng_z, u, v;
    uint32_t prim_id, geom_id, inst_id;
  };

 private:
  friend class Accelerator;
  Record records_[kCapacity];
};

// Which geometry a closest-hit query tests: all of it; only what was added
// with `emits` (its own BVH, so the query costs what the emitters cost: a few
// spheres or quads in most scenes); or all but that (a ray mask on the full
// BVH): camera rays of a scene that hides its emitters pass through them.
enum class GeometrySet { kAll, kEmitters, kNonEmitters };

// How a stream's rays relate to each other. kCoherent: nearly parallel rays
// from nearly one point, such as a path batch's camera rays (the samples of a
// few neighbouring pixels), which Embree then traces as packets that stay
// together: 5-10 % less render time on the bundled scenes (docs/renderer.md,
// "Rays in streams"). For rays that part (every bounce, and shadow rays too) the
// flag costs time, so kIncoherent is the default.
enum class RayCoherence { kIncoherent, kCoherent };

class Accelerator {
 public:
  static Expected<std::unique_ptr<Accelerator>> create();
  ~Accelerator();
  Accelerator(const Accelerator&) = delete;
  Accelerator& operator=(const Accelerator&) = delete;

  // `instanced`: the mesh is in object space and placed by `to_world`, which
  // can change later with set_instance_transform. Otherwise it is in world space.
  // `emits`: the shape is an area emitter (it is in GeometrySet::kEmitters too).
  Status add_mesh(int id, const Vec3f* positions, size_t vertex_count, const uint32_t* indices,
                  size_t triangle_count, bool instanced, const Transform& to_world, bool emits);
  Status add_sphere(int id, Vec3f center, float radius, bool instanced, const Transform& to_world, bool emits);
  Status set_instance_transform(int id, const Transform& to_world);
  // Builds or refits; must be called after adding geometry or moving instances.
  Status commit();

  // Closest hit with t in (tmin, tmax) among `set`. Thread-safe after commit().
  bool intersect(Vec3f origin, Vec3f dir, float tmin, float tmax, RayHit* hit,
                 GeometrySet set = GeometrySet::kAll) const;
  // Any hit with t in (tmin, tmax); `instanced_only`: test only the geometry
  // added with instanced = true (Embree ray masks).
  bool occluded(Vec3f origin, Vec3f dir, float tmin, float tmax, bool instanced_only = false) const;

  // The same queries for the first n (<= RayStreamBuffer::kCapacity) rays of
  // `rays` at once, answered in place (RayStreamBuffer::found/hit,
  // ::occluded), through Embree's stream interface (rtcIntersect1M /
  // rtcOccluded1M): Embree traces the stream in SIMD packets, switching to
  // single-ray traversal where the packet's rays part, which on the bundled
  // scenes is 5-40 % faster per ray than n single queries
  // (docs/renderer.md). The answers are those of intersect() and
  // occluded() (triangles bit for bit; a sphere's t to within an ulp or two,
  // as its packet kernel rounds differently). Occlusion streams test all
  // geometry (there is no instanced_only form). One exception: where two
  // triangles are met at exactly the same t (coplanar overlapping faces, as
  // the Cornell box's ceiling under its light), either is the closest hit and
  // which one Embree reports depends on its traversal order, which a coherent
  // stream changes.
  void intersect_stream(RayStreamBuffer& rays, int n, GeometrySet set = GeometrySet::kAll,
                        RayCoherence coherence = RayCoherence::kIncoherent) const;
  void occluded_stream(RayStreamBuffer& rays, int n) const;

 private:
  struct Impl;
  explicit Accelerator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace gdvr
