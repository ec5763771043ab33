#include "core/accel/accelerator.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cstddef>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace gdvr {
namespace {

const char* embree_error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "none";
    case RTC_ERROR_UNKNOWN: return "unknown";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "?";
}

// Embree reports errors through a device callback; we record the first one so
// the call that caused it can return a Status instead of failing later.
struct ErrorSink {
  std::mutex mutex;
  std::string first_error;
};

void on_embree_error(void* user, RTCError code, const char* message) {
  auto* sink = static_cast<ErrorSink*>(user);
  std::lock_guard<std::mutex> lock(sink->mutex);
  if (sink->first_error.empty())
    sink->first_error = std::string("Embree error (") + embree_error_name(code) + "): " + (message ? message : "");
}

// Ray masks: static geometry answers to bit 0, instanced (animated) geometry
// to bit 1, so a query can skip what cannot have moved; geometry that does not
// emit answers to bit 2 as well (GeometrySet::kNonEmitters).
constexpr unsigned kStaticMask = 1u, kInstancedMask = 2u, kNonEmitterMask = 4u, kAllMask = 0xFFFFFFFFu;

unsigned geometry_mask(bool instanced, bool emits) {
  return (instanced ? kInstancedMask : kStaticMask) | (emits ? 0u : kNonEmitterMask);
}

unsigned ray_mask(GeometrySet set) { return set == GeometrySet::kNonEmitters ? kNonEmitterMask : kAllMask; }

// Embree's FLOAT3X4_COLUMN_MAJOR layout.
void to_embree_matrix(const Transform& t, float out[12]) {
  const Matrix4& m = t.matrix();
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 3; ++row) out[col * 3 + row] = float(m.m[row][col]);
}

}  // namespace

struct Accelerator::Impl {
  ErrorSink errors;
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  RTCScene emitters = nullptr;            // the emitting geometry of `top` again, under the same ids
  std::map<int, RTCGeometry> instances;   // id -> instance geometry (owned by `top`)
  std::vector<RTCScene> child_scenes;     // released in the destructor

  ~Impl() {
    for (RTCScene s : child_scenes) rtcReleaseScene(s);
    if (top) rtcReleaseScene(top);
    if (emitters) rtcReleaseScene(emitters);
    if (device) rtcReleaseDevice(device);
  }

  RTCScene scene(GeometrySet set) const { return set == GeometrySet::kEmitters ? emitters : top; }

  Status take_error(const std::string& what) {
    std::lock_guard<std::mutex> lock(errors.mutex);
    if (errors.first_error.empty()) return Status::Ok();
    Status st = internal_error(what + ": " + errors.first_error);
    errors.first_error.clear();
    return st;
  }

  // Puts `geom` either in the top-level scene under `id`, or in a fresh child
  // scene placed into the top level by an instance with id `id`.
  // An emitting geometry (or its instance) is attached to `emitters` as well:
  // Embree lets one geometry belong to several scenes, so an instance moved by
  // set_instance_transform moves in both.
  Status attach(int id, RTCGeometry geom, bool instanced, const Transform& to_world, bool emits) {
    rtcCommitGeometry(geom);
    if (!instanced) {
      rtcSetGeometryMask(geom, geometry_mask(false, emits));
      rtcCommitGeometry(geom);
      rtcAttachGeometryByID(top, geom, unsigned(id));
      if (emits) rtcAttachGeometryByID(emitters, geom, unsigned(id));
      rtcReleaseGeometry(geom);
      return take_error("attaching geometry " + std::to_string(id));
    }
    RTCScene child = rtcNewScene(device);
    child_scenes.push_back(child);
    rtcAttachGeometryByID(child, geom, 0);
    rtcReleaseGeometry(geom);
    rtcCommitScene(child);
    RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(inst, child);
    float xfm[12];
    to_embree_matrix(to_world, xfm);
    rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    rtcSetGeometryMask(inst, geometry_mask(true, emits));
    rtcCommitGeometry(inst);
    rtcAttachGeometryByID(top, inst, unsigned(id));
    if (emits) rtcAttachGeometryByID(emitters, inst, unsigned(id));
    instances[id] = inst;
    rtcReleaseGeometry(inst);  // the scenes keep their references
    return take_error("instancing geometry " + std::to_string(id));
  }
};

Accelerator::Accelerator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Accelerator::~Accelerator() = default;

Expected<std::unique_ptr<Accelerator>> Accelerator::create() {
  auto impl = std::make_unique<Impl>();
  impl->device = rtcNewDevice(nullptr);
  if (!impl->device)
    return internal_error(std::string("cannot create Embree device: ") +
                          embree_error_name(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(impl->device, on_embree_error, &impl->errors);
  impl->top = rtcNewScene(impl->device);
  rtcSetSceneBuildQuality(impl->top, RTC_BUILD_QUALITY_HIGH);
  impl->emitters = rtcNewScene(impl->device);
  rtcSetSceneBuildQuality(impl->emitters, RTC_BUILD_QUALITY_HIGH);
  GDVR_RETURN_IF_ERROR(impl->take_error("creating Embree scene"));
  return std::unique_ptr<Accelerator>(new Accelerator(std::move(impl)));
}

Status Accelerator::add_mesh(int id, const Vec3f* positions, size_t vertex_count, const uint32_t* indices,
                             size_t triangle_count, bool instanced, const Transform& to_world, bool emits) {
  if (vertex_count == 0 || triangle_count == 0) return invalid_argument("empty mesh " + std::to_string(id));
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // Embree-allocated buffers are padded as Embree's SIMD loads require.
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), vertex_count));
  auto* ix = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(uint32_t), triangle_count));
  if (!v || !ix) {
    rtcReleaseGeometry(geom);
    return impl_->take_error("allocating mesh buffers").ok() ? internal_error("Embree buffer allocation failed")
                                                             : impl_->take_error("mesh");
  }
  for (size_t i = 0; i < vertex_count; ++i) {
    v[3 * i] = positions[i].x;
    v[3 * i + 1] = positions[i].y;
    v[3 * i + 2] = positions[i].z;
  }
  std::copy(indices, indices + 3 * triangle_count, ix);
  return impl_->attach(id, geom, instanced, to_world, emits);
}

Status Accelerator::add_sphere(int id, Vec3f center, float radius, bool instanced, const Transform& to_world,
                               bool emits) {
  if (!(radius > 0) || !std::isfinite(radius) || !is_finite(center))
    return invalid_argument("sphere " + std::to_string(id) + " has a non-positive or non-finite radius/center");
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
  if (!v) {
    rtcReleaseGeometry(geom);
    return internal_error("Embree buffer allocation failed");
  }
  v[0] = center.x;
  v[1] = center.y;
  v[2] = center.z;
  v[3] = radius;
  return impl_->attach(id, geom, instanced, to_world, emits);
}

Status Accelerator::set_instance_transform(int id, const Transform& to_world) {
  auto it = impl_->instances.find(id);
  if (it == impl_->instances.end()) return invalid_argument("geometry " + std::to_string(id) + " is not instanced");
  float xfm[12];
  to_embree_matrix(to_world, xfm);
  rtcSetGeometryTransform(it->second, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
  rtcCommitGeometry(it->second);
  return impl_->take_error("moving instance " + std::to_string(id));
}

Status Accelerator::commit() {
  rtcCommitScene(impl_->top);
  rtcCommitScene(impl_->emitters);
  return impl_->take_error("building the BVH");
}

namespace {

void set_ray(Vec3f o, Vec3f d, float tmin, float tmax, unsigned mask, RTCRay* ray) {
  ray->org_x = o.x;
  ray->org_y = o.y;
  ray->org_z = o.z;
  ray->dir_x = d.x;
  ray->dir_y = d.y;
  ray->dir_z = d.z;
  ray->tnear = tmin;
  ray->tfar = tmax;
  ray->time = 0;
  ray->mask = mask;
  ray->id = 0;
  ray->flags = 0;
}

void clear_hit(RTCRayHit* rh) {
  rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

bool read_hit(const RTCRayHit& rh, RayHit* hit) {
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit->t = rh.ray.tfar;
  hit->id = int(rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rh.hit.instID[0] : rh.hit.geomID);
  hit->prim = rh.hit.primID;
  hit->u = rh.hit.u;
  hit->v = rh.hit.v;
  return true;
}

// rtcOccluded sets tfar to -inf on a hit.
bool read_occluded(const RTCRay& ray) { return ray.tfar == -std::numeric_limits<float>::infinity(); }

// RayStreamBuffer's records are Embree's RTCRayHit, field for field.
using StreamRecord = RayStreamBuffer::Record;
static_assert(sizeof(StreamRecord) == sizeof(RTCRayHit) && alignof(StreamRecord) == alignof(RTCRayHit));
#define GDVR_SAME_OFFSET(ours, theirs) static_assert(offsetof(StreamRecord, ours) == offsetof(RTCRayHit, theirs))
GDVR_SAME_OFFSET(org_x, ray.org_x);
GDVR_SAME_OFFSET(org_y, ray.org_y);
GDVR_SAME_OFFSET(org_z, ray.org_z);
GDVR_SAME_OFFSET(tnear, ray.tnear);
GDVR_SAME_OFFSET(dir_x, ray.dir_x);
GDVR_SAME_OFFSET(dir_y, ray.dir_y);
GDVR_SAME_OFFSET(dir_z, ray.dir_z);
GDVR_SAME_OFFSET(time, ray.time);
GDVR_SAME_OFFSET(tfar, ray.tfar);
GDVR_SAME_OFFSET(mask, ray.mask);
GDVR_SAME_OFFSET(id, ray.id);
GDVR_SAME_OFFSET(flags, ray.flags);
GDVR_SAME_OFFSET(ng_x, hit.Ng_x);
GDVR_SAME_OFFSET(ng_y, hit.Ng_y);
GDVR_SAME_OFFSET(ng_z, hit.Ng_z);
GDVR_SAME_OFFSET(u, hit.u);
GDVR_SAME_OFFSET(v, hit.v);
GDVR_SAME_OFFSET(prim_id, hit.primID);
GDVR_SAME_OFFSET(geom_id, hit.geomID);
GDVR_SAME_OFFSET(inst_id, hit.instID[0]);
#undef GDVR_SAME_OFFSET
static_assert(RTC_MAX_INSTANCE_LEVEL_COUNT == 1 && RayStreamBuffer::kInvalidId == RTC_INVALID_GEOMETRY_ID);

// Embree reads and answers the records in place (they are its own type).
RTCRayHit* embree_records(RayStreamBuffer::Record* records) { return reinterpret_cast<RTCRayHit*>(records); }

}  // namespace

bool Accelerator::intersect(Vec3f o, Vec3f d, float tmin, float tmax, RayHit* hit, GeometrySet set) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  set_ray(o, d, tmin, tmax, ray_mask(set), &rh.ray);
  clear_hit(&rh);
  rtcIntersect1(impl_->scene(set), &context, &rh);
  return read_hit(rh, hit);
}

bool Accelerator::occluded(Vec3f o, Vec3f d, float tmin, float tmax, bool instanced_only) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray;
  set_ray(o, d, tmin, tmax, instanced_only ? kInstancedMask : kAllMask, &ray);
  rtcOccluded1(impl_->top, &context, &ray);
  return read_occluded(ray);
}

void Accelerator::intersect_stream(RayStreamBuffer& rays, int n, GeometrySet set, RayCoherence coherence) const {
  if (n <= 0) return;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);  // incoherent unless told: the flag slows rays that part
  if (coherence == RayCoherence::kCoherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  RTCRayHit* records = embree_records(rays.records_);
  RTCScene scene = impl_->scene(set);
  // The records' masks stay kAllMask between queries (RayStreamBuffer sets
  // them once); a masked query sets and restores its own.
  const bool masked = set == GeometrySet::kNonEmitters;
  if (masked)
    for (int i = 0; i < n; ++i) records[i].ray.mask = ray_mask(set);
  if (n == 1) rtcIntersect1(scene, &context, records);  // the stream set-up buys nothing for one ray
  else rtcIntersect1M(scene, &context, records, unsigned(n), sizeof(RTCRayHit));
  if (masked)
    for (int i = 0; i < n; ++i) records[i].ray.mask = kAllMask;
}

void Accelerator::occluded_stream(RayStreamBuffer& rays, int n) const {
  if (n <= 0) return;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit* records = embree_records(rays.records_);
  if (n == 1) rtcOccluded1(impl_->top, &context, &records->ray);
  else rtcOccluded1M(impl_->top, &context, &records->ray, unsigned(n), sizeof(RTCRayHit));
}

}  // namespace gdvr
