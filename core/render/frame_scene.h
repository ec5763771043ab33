// The scene in world space at one frame: the accelerator, world-space shape
// data for shading, and the tables emitter sampling needs. Built once per job;
// update() moves what an animation changed (instance transforms, emitter and
// camera placement) without rebuilding static geometry.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/accel/accelerator.h"
#include "core/emitter/area_emitter.h"
#include "core/emitter/emitter_sample.h"
#include "core/emitter/environment_emitter.h"
#include "core/math/bounds.h"
#include "core/math/distribution.h"
#include "core/math/rng.h"
#include "core/render/vector_scene.h"
#include "core/render/ray.h"
#include "core/scene/scene.h"

namespace gdvr {

// The shadow ray from `si` towards the sampled emitter point, stopping short
// of it (unbounded for an emitter at infinity). As Mitsuba's spawn_ray_to, it
// is aimed from the offset origin at the emitter point, not cast along es.d
// from there: a ray moved sideways by the offset enters a sphere light early
// where it grazes it, so samples near the sphere's silhouette were found
// occluded by the light itself (2 % of the direct light 0.3 from a sphere of
// radius 0.04; EmitterSampleTest.ShadowRaysReachSphereSilhouette).
inline Ray shadow_ray(const SurfaceInteraction& si, const EmitterSample& es) {
  if (std::isinf(es.dist)) return si.spawn_ray(es.d);
  const Vec3f o = si.offset_p(es.d);
  const Vec3f to = (si.p + es.d * es.dist) - o;
  const float len = length(to);
  if (!(len > 0)) return Ray{o, es.d, 0.0f, 0.0f};
  return Ray{o, to * (1.0f / len), 0.0f, len * (1.0f - kShadowEpsilon)};
}

// Ray i of the accelerator's next stream query.
inline void set_stream_ray(RayStreamBuffer& stream, int i, const Ray& r) { stream.set(i, r.o, r.d, r.tmin, r.tmax); }

class FrameScene {
 public:
  // `animated_shapes[i]` marks shapes whose transform changes during the job
  // (they are instanced). May be empty: nothing animates.
  static Expected<std::unique_ptr<FrameScene>> create(const Scene& scene, const std::vector<bool>& animated_shapes);
  ~FrameScene();

  // Takes the transforms of animated shapes, all emitters and the camera from
  // `scene` (the same scene after apply_animation).
  Status update(const Scene& scene);

  const Scene& scene() const { return scene_; }
  const Accelerator& accelerator() const { return *accel_; }
  bool has_environment() const { return environment_ >= 0; }

  bool intersect(const Ray& ray, SurfaceInteraction* si, GeometrySet set = GeometrySet::kAll) const;
  // The closest hit without its shading data (no interpolation, no frame),
  // for callers that need only what was hit; interaction() completes it.
  bool intersect_hit(const Ray& ray, RayHit* hit, GeometrySet set = GeometrySet::kAll) const {
    return accel_->intersect(ray.o, ray.d, ray.tmin, ray.tmax, hit, set);
  }
  // What camera rays can hit. A scene that hides its emitters
  // (RenderDefaults::hide_emitters) shows what lies behind an area light, as
  // Mitsuba 3's path integrators do (they skip area emitters along camera
  // rays); the light still lights the scene, and later path segments still
  // meet it. Every camera ray, of base and offset paths alike, asks this.
  bool hides_emitters() const { return scene_.defaults.hide_emitters; }
  GeometrySet camera_geometry() const { return hides_emitters() ? GeometrySet::kNonEmitters : GeometrySet::kAll; }
  bool intersect_camera_ray(const Ray& ray, SurfaceInteraction* si) const {
    return intersect(ray, si, camera_geometry());
  }
  // The same among the area emitters' shapes only (GeometrySet::kEmitters).
  bool intersect_emitter_hit(const Ray& ray, RayHit* hit) const {
    return accel_->intersect(ray.o, ray.d, ray.tmin, ray.tmax, hit, GeometrySet::kEmitters);
  }
  void interaction(const Ray& ray, const RayHit& hit, SurfaceInteraction* si) const;
  bool occluded(const Ray& ray) const { return accel_->occluded(ray.o, ray.d, ray.tmin, ray.tmax); }
  // Occluded by an animated shape (the only ones whose place can change
  // between frames; static shapes are skipped).
  bool occluded_by_animated(const Ray& ray) const {
    return accel_->occluded(ray.o, ray.d, ray.tmin, ray.tmax, /* instanced_only = */ true);
  }

  // ---- Emitters ----
  // Samples an emitter uniformly, then a direction towards it. Visibility is
  // NOT tested here (the integrator traces the shadow ray and counts it).
  EmitterSample sample_emitter_direction(const SurfaceInteraction& ref, float u_select, Vec2f u) const;
  // Solid-angle pdf (with selection) that sample_emitter_direction would have
  // produced `hit` from `ref_p`.
  float pdf_emitter_direction(Vec3f ref_p, const SurfaceInteraction& hit) const;
  float pdf_environment_direction(Vec3f d) const;
  // What a ray escaping along `d` sees: the environment's radiance and the
  // solid-angle pdf (with selection) of sampling `d` as an emitter. One
  // direction-to-uv conversion for both (its atan2 and acos were 4 % of PT on
  // matpreview when eval_environment and pdf_environment_direction each did it).
  struct EnvironmentLookup {
    Rgb radiance;
    float pdf = 0;
  };
  EnvironmentLookup environment_along(Vec3f d) const;
  // Starts loading the memory that sample_emitter_direction(., u_select, u)
  // will most likely read, where that is a table too big for the cache (an
  // environment map's alias slots and texels). An integrator that knows its
  // next emitter sample's numbers before it traces the ray to that vertex
  // calls this first, so that the loads arrive while Embree traverses.
  void prefetch_emitter_sample(float u_select, Vec2f u) const;
  // The same for the emitter sample whose numbers `sampler` draws next (a
  // copy reads them ahead; the caller's stream is untouched). Only scenes with
  // an environment have such tables.
  void prefetch_next_emitter_sample(Sampler ahead) const {
    if (!has_environment()) return;
    const float u_select = ahead.next_1d();
    prefetch_emitter_sample(u_select, ahead.next_2d());
  }
  // Radiance leaving an emitting surface towards -ray (area emitters).
  Rgb eval_area_emitter(const SurfaceInteraction& si) const;
  // Radiance arriving along a ray that escaped the scene.
  Rgb eval_environment(Vec3f d) const;
  int emitter_of_shape(int shape) const { return scene_.shapes[size_t(shape)].emitter; }
  // The world bounds of every area emitter's shape at this frame: where a ray
  // can see emission, apart from the environment (has_environment(); point,
  // spot and directional lights are never hit by a ray).
  std::vector<Bounds3f> area_emitter_bounds() const;

  // ---- The vector path batch (vector_batch.h) ----
  // The scene as per-triangle records (vector_scene.h) where it has an
  // emitter and a shape the vector kernel shades; else null, and
  // why_not_vector() names what the scene has that the records cannot hold.
  const VectorScene* vector_scene() const { return vector_.get(); }
  const std::string& why_not_vector() const { return why_not_vector_; }

 private:
  friend class VectorScene;  // reads ShapeState to lay out its records
  struct ShapeState {
    std::shared_ptr<const TriangleMesh> mesh;  // world space if !instanced
    std::vector<Vec3f> face_normals;           // unit, same space as `mesh` (saves a cross + sqrt per hit)
    // Static meshes only: each triangle's SurfaceInteraction::offset_floor
    // (nine abs and eight max per hit otherwise).
    std::vector<float> offset_floors;
    // Per triangle: its three vertex normals equal the face normal, so the
    // shading normal needs no interpolation (box-like meshes, flat quads).
    // All 1 for a mesh without vertex normals (or with face_normals set).
    std::vector<uint8_t> flat;
    bool vertex_normals = false;  // shading interpolates the mesh's vertex normals
    // The BSDF is anisotropic, so the shading frame follows dp/du
    // (Frame::along_tangent); otherwise only its normal matters.
    bool tangent_frame = false;
    bool instanced = false;
    Transform to_world, to_object;
    float handedness = 1;  // sign of det(to_world): a mirroring transform flips cross-product normals
    Vec3f center;       // sphere, world space
    float radius = 0;   // sphere, world space
    Distribution1D triangle_areas;  // area emitters only
    std::vector<EmitterTriangle> emitter_triangles;  // area emitters only
    float area = 0;
  };
  FrameScene() = default;
  Status build_shape_state(size_t i, bool animated);
  Status prepare_emitters();
  // The shading normal at barycentrics (b1, b2) of triangle `tri`: the face
  // normal where the triangle is flat (inline: the common case, and the call
  // cost more than the test), else the interpolated vertex normals. Under a
  // mirroring instance transform the face normal flips but vertex normals do
  // not, so a flat triangle of a mesh with vertex normals interpolates then.
  Vec3f shading_normal(const ShapeState& s, uint32_t tri, float b1, float b2, Vec3f face_n) const {
    if (shades_with_face_normal(s, tri)) return face_n;
    return interpolated_normal(s, tri, b1, b2, face_n);
  }
  static bool shades_with_face_normal(const ShapeState& s, size_t tri) {
    return s.flat[tri] && (s.handedness > 0 || !s.vertex_normals);
  }
  // Triangle `tri`'s unit face normal in world space (before flip_normals).
  static Vec3f world_face_normal(const ShapeState& s, size_t tri) {
    return s.instanced ? normalize(s.to_world.normal(s.face_normals[tri])) * s.handedness : s.face_normals[tri];
  }
  Vec3f interpolated_normal(const ShapeState& s, uint32_t tri, float b1, float b2, Vec3f face_n) const;
  EmitterSample sample_area_emitter(const Emitter& em, Vec3f ref_p, Vec2f u, float select_pdf,
                                    EmitterSample es) const;

  Scene scene_;
  std::unique_ptr<Accelerator> accel_;
  std::vector<ShapeState> shapes_;
  std::vector<EnvmapTables> envmaps_;  // parallel to scene_.emitters (empty unless envmap)
  int environment_ = -1;               // index of the constant/envmap emitter
  std::unique_ptr<VectorScene> vector_;
  std::string why_not_vector_;
};

}  // namespace gdvr
