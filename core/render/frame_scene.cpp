#include "core/render/frame_scene.h"

#include <cmath>
#include <string>

#include "core/emitter/directional_emitter.h"
#include "core/emitter/point_emitter.h"
#include "core/math/arctan.h"

namespace gdvr {
namespace {

float determinant_sign(const Transform& t) {
  const auto& m = t.matrix().m;
  double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return det < 0 ? -1.0f : 1.0f;
}

float triangle_area(Vec3f a, Vec3f b, Vec3f c) { return 0.5f * length(cross(b - a, c - a)); }

// dp/du of a triangle from its uv parametrization, as Mitsuba 3's meshes
// define it. A mesh without uvs, or a triangle whose uvs are degenerate,
// takes Mitsuba's coordinate_system of the face normal (Frame's tangent).
Vec3f triangle_dpdu(const TriangleMesh& m, uint32_t i0, uint32_t i1, uint32_t i2, Vec3f p0, Vec3f p1, Vec3f p2,
                    Vec3f face_n) {
  if (!m.uvs.empty()) {
    const Vec2f d1 = m.uvs[i1] - m.uvs[i0], d2 = m.uvs[i2] - m.uvs[i0];
    const float det = d1.x * d2.y - d1.y * d2.x;
    if (det != 0.0f && std::isfinite(det)) return ((p1 - p0) * d2.y - (p2 - p0) * d1.y) * (1.0f / det);
  }
  return Frame(face_n).s;
}

// The scale of the coordinates a hit on this triangle is interpolated from
// (SurfaceInteraction::offset_floor), in world space.
// The distance along `ray` to the sphere's root nearest Embree's `embree_t`,
// solved in double. Embree's single-ray and packet kernels round a sphere's
// t differently (by an ulp or two), so the hit point is computed here, from
// the ray alone, and is the same whichever kernel found the hit (the path
// tracer's batches cast streams, trace_path single rays: path_batch.h). The
// discriminant is r^2 - |f|^2 with f the ray's closest approach to the
// centre (pbrt-v4's form), which does not cancel for distant spheres.
float sphere_hit_distance(const Ray& ray, Vec3f center, float radius, float embree_t) {
  const double ox = double(ray.o.x) - center.x, oy = double(ray.o.y) - center.y, oz = double(ray.o.z) - center.z;
  const double dx = ray.d.x, dy = ray.d.y, dz = ray.d.z;
  const double dd = dx * dx + dy * dy + dz * dz;
  if (!(dd > 0)) return embree_t;
  const double mid = -(ox * dx + oy * dy + oz * dz) / dd;  // closest approach
  const double fx = ox + mid * dx, fy = oy + mid * dy, fz = oz + mid * dz;
  const double r = radius;
  const double half_chord_sq = (r * r - (fx * fx + fy * fy + fz * fz)) / dd;
  if (!(half_chord_sq > 0)) return float(mid);  // grazing: Embree hit within its rounding
  const double half_chord = std::sqrt(half_chord_sq);
  const double near = mid - half_chord, far = mid + half_chord;
  return float(std::abs(near - embree_t) <= std::abs(far - embree_t) ? near : far);
}

}  // namespace

Expected<std::unique_ptr<FrameScene>> FrameScene::create(const Scene& scene, const std::vector<bool>& animated) {
  std::unique_ptr<FrameScene> fs(new FrameScene());
  fs->scene_ = scene;
  auto accel = Accelerator::create();
  if (!accel.ok()) return accel.status();
  fs->accel_ = std::move(accel.value());
  fs->shapes_.resize(scene.shapes.size());
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    bool is_animated = i < animated.size() && animated[i];
    GDVR_RETURN_IF_ERROR(fs->build_shape_state(i, is_animated));
  }
  GDVR_RETURN_IF_ERROR(fs->accel_->commit());
  GDVR_RETURN_IF_ERROR(fs->prepare_emitters());
  fs->vector_ = VectorScene::build(*fs, &fs->why_not_vector_);
  return fs;
}

FrameScene::~FrameScene() = default;

Status FrameScene::build_shape_state(size_t i, bool animated) {
  const Shape& shape = scene_.shapes[i];
  ShapeState& s = shapes_[i];
  s.instanced = animated;
  s.to_world = shape.to_world;
  s.to_object = shape.to_world.inverse();
  s.handedness = determinant_sign(shape.to_world);
  s.tangent_frame = scene_.bsdfs[size_t(shape.bsdf)].is_anisotropic();
  const std::string name = "shape " + std::to_string(i) + (shape.id.empty() ? "" : " ('" + shape.id + "')");
  const bool emits = shape.emitter >= 0;
  if (shape.type == ShapeType::kSphere) {
    s.center = shape.to_world.point(Vec3f(0.0f));
    float rx = length(shape.to_world.vector({1, 0, 0})), ry = length(shape.to_world.vector({0, 1, 0})),
          rz = length(shape.to_world.vector({0, 0, 1}));
    if (std::abs(rx - ry) > 1e-4f * rx || std::abs(rx - rz) > 1e-4f * rx)
      return invalid_argument(name + ": a sphere's to_world must scale uniformly");
    s.radius = rx;
    s.area = 4.0f * kPi * s.radius * s.radius;
    if (animated) return accel_->add_sphere(int(i), Vec3f(0.0f), 1.0f, true, shape.to_world, emits);
    return accel_->add_sphere(int(i), s.center, s.radius, false, Transform(), emits);
  }
  if (!shape.mesh || shape.mesh->triangle_count() == 0) return invalid_argument(name + " has no triangles");
  if (animated) {
    s.mesh = shape.mesh;
  } else {
    // Bake static meshes into world space once: shading then needs no transform.
    auto world = std::make_shared<TriangleMesh>(*shape.mesh);
    for (Vec3f& p : world->positions) p = shape.to_world.point(p);
    for (Vec3f& n : world->normals) n = normalize(shape.to_world.normal(n));
    s.mesh = world;
  }
  const TriangleMesh& m = *s.mesh;
  for (const Vec3f& p : m.positions)
    if (!is_finite(p)) return invalid_argument(name + " has a non-finite vertex position");
  s.face_normals.resize(m.triangle_count());
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    Vec3f p0 = m.positions[m.indices[3 * t]], p1 = m.positions[m.indices[3 * t + 1]],
          p2 = m.positions[m.indices[3 * t + 2]];
    s.face_normals[t] = normalize(cross(p1 - p0, p2 - p0));
  }
  if (!animated) {
    s.offset_floors.resize(m.triangle_count());
    for (size_t t = 0; t < m.triangle_count(); ++t)
      s.offset_floors[t] = triangle_offset_floor(m.positions[m.indices[3 * t]], m.positions[m.indices[3 * t + 1]],
                                                 m.positions[m.indices[3 * t + 2]]);
  }
  s.flat.assign(m.triangle_count(), 1);
  s.vertex_normals = !m.normals.empty() && !shape.face_normals;
  if (s.vertex_normals) {
    for (size_t t = 0; t < m.triangle_count(); ++t)
      for (int k = 0; k < 3; ++k) {
        Vec3f vn = m.normals[m.indices[3 * t + k]];
        // Object-space normals of an instanced mesh are compared in object space too.
        if (!(dot(vn, s.face_normals[t]) > 1.0f - 1e-6f) || std::abs(length_squared(vn) - 1.0f) > 1e-5f)
          s.flat[t] = 0;
      }
  }
  return accel_->add_mesh(int(i), m.positions.data(), m.positions.size(), m.indices.data(), m.triangle_count(),
                          animated, shape.to_world, emits);
}

Status FrameScene::prepare_emitters() {
  // An environment map's sampling tables depend on its image alone: an
  // update() that rotates it keeps them.
  std::vector<EnvmapTables> previous = std::move(envmaps_);
  envmaps_.assign(scene_.emitters.size(), EnvmapTables());
  environment_ = -1;
  for (size_t e = 0; e < scene_.emitters.size(); ++e) {
    const Emitter& em = scene_.emitters[e];
    if (em.type == EmitterType::kConstant || em.type == EmitterType::kEnvmap) {
      if (environment_ >= 0) return invalid_argument("the scene has more than one environment emitter");
      environment_ = int(e);
    }
    if (em.type == EmitterType::kEnvmap) {
      if (!em.envmap || em.envmap->width() < 2 || em.envmap->height() < 3)
        return invalid_argument("envmap emitter " + em.id + ": image missing or smaller than 2x3");
      if (e < previous.size() && previous[e].image == em.envmap) {
        envmaps_[e] = std::move(previous[e]);
      } else {
        envmaps_[e].image = em.envmap;
        envmaps_[e].distribution = envmap_distribution(*em.envmap);
      }
      envmaps_[e].to_local = em.to_world.inverse();
    }
    if (em.type == EmitterType::kArea) {
      if (em.shape < 0 || size_t(em.shape) >= shapes_.size())
        return invalid_argument("area emitter " + std::to_string(e) + " is not attached to a shape");
      ShapeState& s = shapes_[size_t(em.shape)];
      const Shape& shape = scene_.shapes[size_t(em.shape)];
      if (shape.type == ShapeType::kMesh) {
        const TriangleMesh& m = *s.mesh;
        std::vector<float> areas(m.triangle_count());
        s.emitter_triangles.resize(m.triangle_count());
        for (size_t t = 0; t < areas.size(); ++t) {
          EmitterTriangle& tri = s.emitter_triangles[t];
          tri.p0 = m.positions[m.indices[3 * t]];
          tri.p1 = m.positions[m.indices[3 * t + 1]];
          tri.p2 = m.positions[m.indices[3 * t + 2]];
          if (s.instanced) tri.p0 = s.to_world.point(tri.p0), tri.p1 = s.to_world.point(tri.p1), tri.p2 = s.to_world.point(tri.p2);
          // What interaction() evaluates at a hit, so that a sampled point and
          // a hit on it agree bit for bit.
          tri.n = world_face_normal(s, t);
          tri.face_normal = shades_with_face_normal(s, t);
          if (shape.flip_normals) tri.n = -tri.n;
          areas[t] = triangle_area(tri.p0, tri.p1, tri.p2);
        }
        s.triangle_areas = Distribution1D(areas);
        s.area = float(s.triangle_areas.total());
        if (!(s.area > 0)) return invalid_argument("area emitter on a shape with zero area");
      }
    }
  }
  return Status::Ok();
}

Status FrameScene::update(const Scene& scene) {
  if (scene.shapes.size() != scene_.shapes.size() || scene.emitters.size() != scene_.emitters.size())
    return failed_precondition("FrameScene::update: the scene's structure changed");
  bool moved = false;
  for (size_t i = 0; i < shapes_.size(); ++i) {
    const Transform& t = scene.shapes[i].to_world;
    if (t == shapes_[i].to_world) continue;
    if (!shapes_[i].instanced)
      return failed_precondition("shape " + std::to_string(i) + " moved but was not marked animated");
    shapes_[i].to_world = t;
    shapes_[i].to_object = t.inverse();
    shapes_[i].handedness = determinant_sign(t);
    scene_.shapes[i].to_world = t;
    if (scene_.shapes[i].type == ShapeType::kSphere) {
      shapes_[i].center = t.point(Vec3f(0.0f));
      shapes_[i].radius = length(t.vector({1, 0, 0}));
      shapes_[i].area = 4.0f * kPi * shapes_[i].radius * shapes_[i].radius;
    }
    GDVR_RETURN_IF_ERROR(accel_->set_instance_transform(int(i), t));
    moved = true;
  }
  if (moved) GDVR_RETURN_IF_ERROR(accel_->commit());
  scene_.emitters = scene.emitters;
  scene_.camera = scene.camera;
  GDVR_RETURN_IF_ERROR(prepare_emitters());
  if (vector_ && !vector_->refresh(*this, &why_not_vector_)) vector_.reset();
  return Status::Ok();
}

// Mitsuba's smooth shading normal (shading_normal() has ruled out the flat case).
Vec3f FrameScene::interpolated_normal(const ShapeState& s, uint32_t tri, float b1, float b2, Vec3f face_n) const {
  if (!s.vertex_normals) return face_n;
  const TriangleMesh& m = *s.mesh;
  uint32_t i0 = m.indices[3 * tri], i1 = m.indices[3 * tri + 1], i2 = m.indices[3 * tri + 2];
  Vec3f interp = m.normals[i0] * (1.0f - b1 - b2) + m.normals[i1] * b1 + m.normals[i2] * b2;
  if (s.instanced) interp = s.to_world.normal(interp);
  interp = normalize(interp);
  return (is_finite(interp) && length_squared(interp) > 0.5f) ? interp : face_n;
}

bool FrameScene::intersect(const Ray& ray, SurfaceInteraction* si, GeometrySet set) const {
  RayHit hit;
  if (!accel_->intersect(ray.o, ray.d, ray.tmin, ray.tmax, &hit, set)) return false;
  interaction(ray, hit, si);
  return true;
}

void FrameScene::interaction(const Ray& ray, const RayHit& hit, SurfaceInteraction* si) const {
  const Shape& shape = scene_.shapes[size_t(hit.id)];
  const ShapeState& s = shapes_[size_t(hit.id)];
  si->t = hit.t;
  si->shape = hit.id;
  si->prim = hit.prim;
  Vec3f ns, dpdu;
  if (shape.type == ShapeType::kSphere) {
    si->t = sphere_hit_distance(ray, s.center, s.radius, hit.t);
    Vec3f local = normalize(ray.o + ray.d * si->t - s.center);
    si->p = s.center + local * s.radius;  // re-project: tighter than o + t d
    si->n = local;
    ns = local;
    // Sphere uv in the object frame (Mitsuba: phi / 2pi, theta / pi).
    Vec3f lo = normalize(s.to_object.vector(local));
    const float phi = atan2_turns(lo.y, lo.x);
    si->uv = {phi < 0.0f ? phi + 1.0f : phi, acos_half_turns(lo.z)};
    if (s.tangent_frame) dpdu = s.to_world.vector(Vec3f(-lo.y, lo.x, 0.0f));  // d/d(phi), as Mitsuba's sphere
    si->offset_floor = std::min(1.0f, max_abs_component(s.center) + s.radius);
  } else {
    const TriangleMesh& m = *s.mesh;
    uint32_t i0 = m.indices[3 * hit.prim], i1 = m.indices[3 * hit.prim + 1], i2 = m.indices[3 * hit.prim + 2];
    float b1 = hit.u, b2 = hit.v, b0 = 1.0f - b1 - b2;
    Vec3f p0 = m.positions[i0], p1 = m.positions[i1], p2 = m.positions[i2];
    if (s.instanced) p0 = s.to_world.point(p0), p1 = s.to_world.point(p1), p2 = s.to_world.point(p2);
    si->p = p0 * b0 + p1 * b1 + p2 * b2;
    si->offset_floor = s.instanced ? triangle_offset_floor(p0, p1, p2) : s.offset_floors[hit.prim];
    si->n = world_face_normal(s, hit.prim);
    ns = shading_normal(s, hit.prim, b1, b2, si->n);
    si->uv = m.uvs.empty() ? Vec2f(b1, b2) : m.uvs[i0] * b0 + m.uvs[i1] * b1 + m.uvs[i2] * b2;
    if (s.tangent_frame) dpdu = triangle_dpdu(m, i0, i1, i2, p0, p1, p2, si->n);
  }
  if (shape.flip_normals) {
    si->n = -si->n;
    ns = -ns;
  }
  si->sh_frame = s.tangent_frame ? Frame::along_tangent(ns, dpdu) : Frame(ns);
  si->wi = si->sh_frame.to_local(-ray.d);
}

// ---- Emitters ----

std::vector<Bounds3f> FrameScene::area_emitter_bounds() const {
  std::vector<Bounds3f> bounds;
  for (const Emitter& em : scene_.emitters) {
    if (em.type != EmitterType::kArea) continue;
    const ShapeState& s = shapes_[size_t(em.shape)];
    Bounds3f b;
    if (scene_.shapes[size_t(em.shape)].type == ShapeType::kSphere) {
      b.expand(s.center - Vec3f(s.radius));
      b.expand(s.center + Vec3f(s.radius));
    } else {
      for (Vec3f p : s.mesh->positions) b.expand(s.instanced ? s.to_world.point(p) : p);
    }
    bounds.push_back(b);
  }
  return bounds;
}

// Uniform emitter selection, as Mitsuba 3 does (keeps noise comparable),
// then the emitter kind's own sampling (core/emitter/).
EmitterSample FrameScene::sample_emitter_direction(const SurfaceInteraction& ref, float u_select, Vec2f u) const {
  EmitterSample es;
  size_t count = scene_.emitters.size();
  if (count == 0) return es;
  float scaled = u_select * float(count);
  size_t index = std::min(size_t(scaled), count - 1);
  float select_pdf = 1.0f / float(count);
  const Emitter& em = scene_.emitters[index];
  es.emitter = int(index);

  switch (em.type) {
    case EmitterType::kArea: return sample_area_emitter(em, ref.p, u, select_pdf, es);
    case EmitterType::kPoint:
    case EmitterType::kSpot: return sample_point_emitter(em, ref.p, select_pdf, es);
    case EmitterType::kDirectional: return sample_directional_emitter(em, select_pdf, es);
    case EmitterType::kConstant: return sample_constant_emitter(em, u, select_pdf, es);
    case EmitterType::kEnvmap: return sample_envmap_emitter(em, envmaps_[index], u, select_pdf, es);
  }
  return es;
}

// The shape's world-space geometry is FrameScene's; the point and its
// density are area_emitter.h's. A mesh whose vertex normals are not its face
// normal emits along the normal interaction() would interpolate there.
EmitterSample FrameScene::sample_area_emitter(const Emitter& em, Vec3f ref_p, Vec2f u, float select_pdf,
                                              EmitterSample es) const {
  const ShapeState& s = shapes_[size_t(em.shape)];
  const Shape& shape = scene_.shapes[size_t(em.shape)];
  AreaEmitterPoint pt;
  if (shape.type == ShapeType::kSphere) {
    pt = sample_sphere_emitter_point(s.center, s.radius, shape.flip_normals, ref_p, u);
  } else {
    size_t t;
    Vec2f b;
    pt = sample_triangle_emitter_point(s.triangle_areas, s.emitter_triangles, u, &t, &b);
    if (!s.emitter_triangles[t].face_normal) {
      // pt.n has flip_normals applied; interpolated_normal() takes and
      // returns normals before it (its fallback is the face normal).
      const Vec3f face_n = shape.flip_normals ? -pt.n : pt.n;
      pt.n = interpolated_normal(s, uint32_t(t), b.x, b.y, face_n);
      if (shape.flip_normals) pt.n = -pt.n;
    }
  }
  return area_emitter_sample(ref_p, pt, s.area, em.radiance, select_pdf, es);
}

float FrameScene::pdf_emitter_direction(Vec3f ref_p, const SurfaceInteraction& hit) const {
  int e = emitter_of_shape(hit.shape);
  if (e < 0) return 0.0f;
  const ShapeState& s = shapes_[size_t(hit.shape)];
  const float pdf = scene_.shapes[size_t(hit.shape)].type == ShapeType::kSphere
                        ? sphere_emitter_pdf(s.center, s.radius, s.area, ref_p, hit.p, hit.sh_frame.n)
                        : mesh_emitter_pdf(s.area, ref_p, hit.p, hit.sh_frame.n);
  return pdf / float(scene_.emitters.size());
}

float FrameScene::pdf_environment_direction(Vec3f d) const {
  if (environment_ < 0) return 0.0f;
  const Emitter& em = scene_.emitters[size_t(environment_)];
  const float select_pdf = 1.0f / float(scene_.emitters.size());
  if (em.type == EmitterType::kConstant) return kInvFourPi * select_pdf;
  return envmap_pdf(envmaps_[size_t(environment_)], d) * select_pdf;
}

FrameScene::EnvironmentLookup FrameScene::environment_along(Vec3f d) const {
  EnvironmentLookup out;
  if (environment_ < 0) return out;
  const Emitter& em = scene_.emitters[size_t(environment_)];
  const float select_pdf = 1.0f / float(scene_.emitters.size());
  if (em.type == EmitterType::kConstant) {
    out.radiance = em.radiance;
    out.pdf = kInvFourPi * select_pdf;
    return out;
  }
  const EnvmapLookup lookup = envmap_along(em, envmaps_[size_t(environment_)], d);
  out.radiance = lookup.radiance;
  out.pdf = lookup.pdf * select_pdf;
  return out;
}

void FrameScene::prefetch_emitter_sample(float u_select, Vec2f u) const {
  const size_t count = scene_.emitters.size();
  if (count == 0) return;
  const size_t index = std::min(size_t(u_select * float(count)), count - 1);
  if (scene_.emitters[index].type != EmitterType::kEnvmap) return;
  prefetch_envmap_sample(envmaps_[index], u);
}

Rgb FrameScene::eval_area_emitter(const SurfaceInteraction& si) const {
  int e = emitter_of_shape(si.shape);
  if (e < 0 || si.wi.z <= 0) return Rgb(0.0f);
  return scene_.emitters[size_t(e)].radiance;
}

Rgb FrameScene::eval_environment(Vec3f d) const {
  if (environment_ < 0) return Rgb(0.0f);
  const Emitter& em = scene_.emitters[size_t(environment_)];
  if (em.type == EmitterType::kConstant) return em.radiance;
  return eval_envmap(em, envmaps_[size_t(environment_)], d);
}

}  // namespace gdvr
