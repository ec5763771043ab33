#include "core/render/frame_scene.h"

#include <cmath>
#include <string>

#include "core/math/arctan.h"
#include "core/math/sampling.h"

namespace gdvr {
namespace {

// Mitsuba's lat-long convention (envmap.cpp): u = atan2(x, -z) / 2pi, v = acos(y) / pi.
Vec2f direction_to_uv(Vec3f d) {
  const float u = atan2_turns(d.x, -d.z);
  // u is in [-1/2, 1/2]: u - floor(u) without floor (a libm call or a long
  // inline sequence without SSE4.1).
  return {u < 0.0f ? u + 1.0f : u, acos_half_turns(d.y)};
}

Vec3f uv_to_direction(Vec2f uv, float* sin_theta) {
  const SinCos theta = sincos_turns(0.5f * uv.y), phi = sincos_turns(uv.x);
  *sin_theta = theta.sin;
  return {phi.sin * theta.sin, theta.cos, -phi.cos * theta.sin};
}

// The four texels of a bilinear lookup, as Mitsuba 3's envmap: texel (i, j)
// at u = (i + 1/2) / width, periodic in u (the lookup between the last and the
// first column wraps), and at v = j / (height - 1). Texels at u = i / width
// (the convention of earlier Mitsuba versions) shifted the whole map by half a
// texel: matpreview rendered 0.3 % brighter than Mitsuba 3.9.
struct BilinearTexels {
  int x0, x1, y0, y1;
  float fx, fy;
};

BilinearTexels envmap_texels(const Image& img, Vec2f uv) {
  int w = img.width(), h = img.height();
  // x counts from the centre of the column before column 0 (the last one,
  // periodically): x in [1/2, w + 1/2] for u in [0, 1], so truncation is
  // floor (std::floor is a libm call without SSE4.1; this runs for every
  // environment lookup and prefetch).
  float x = std::max(0.0f, uv.x) * float(w) + 0.5f, y = std::max(0.0f, uv.y) * float(h - 1);  // NaN -> 0
  int xb = std::min(int(x), w), y0 = std::min(int(y), h - 1);
  float fx = std::clamp(x - float(xb), 0.0f, 1.0f), fy = std::clamp(y - float(y0), 0.0f, 1.0f);
  // Columns xb - 1 and xb, periodic: xb ∈ [0, w] (compares, not a division).
  int x0 = xb - 1, x1 = xb;
  if (x0 < 0) x0 += w;
  if (x1 >= w) x1 -= w;
  return {x0, x1, y0, std::min(y0 + 1, h - 1), fx, fy};
}

Rgb envmap_lookup(const Image& img, Vec2f uv) {
  const BilinearTexels t = envmap_texels(img, uv);
  return (img.rgb(t.x0, t.y0) * (1 - t.fx) + img.rgb(t.x1, t.y0) * t.fx) * (1 - t.fy) +
         (img.rgb(t.x0, t.y1) * (1 - t.fx) + img.rgb(t.x1, t.y1) * t.fx) * t.fy;
}

// The piecewise-constant density that environment samples are drawn from:
// per cell of a grid finer than the texels (the lookup is bilinear between
// texel centres, so coarse cells leave L / pdf varying by up to 2x within a
// cell around a small bright feature: 1.6-1.8x Mitsuba's variance, whose
// sampling follows the bilinear lookup), the cell's luminance (its centre
// and corners, so that no cell where the map is not black gets zero weight)
// times sin(theta). 4 x 4 cells a texel matched Mitsuba's variance on the
// generated scenes; maps with more than 256K texels get fewer, which keeps the
// tables under 4M cells (their texels are small already).
Distribution2D envmap_distribution(const Image& img) {
  int k = 4;
  while (k > 1 && size_t(k) * k * size_t(img.width()) * size_t(img.height()) > (size_t(1) << 22)) k /= 2;
  const int w = k * img.width(), h = k * img.height();
  std::vector<float> weights(size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    const float sin_theta = std::sin(kPi * (float(y) + 0.5f) / float(h));
    const float v0 = float(y) / float(h), v1 = float(y + 1) / float(h);
    for (int x = 0; x < w; ++x) {
      const float u0 = float(x) / float(w), u1 = float(x + 1) / float(w);
      const float centre = luminance(envmap_lookup(img, {0.5f * (u0 + u1), 0.5f * (v0 + v1)}));
      const float corners = luminance(envmap_lookup(img, {u0, v0})) + luminance(envmap_lookup(img, {u1, v0})) +
                            luminance(envmap_lookup(img, {u0, v1})) + luminance(envmap_lookup(img, {u1, v1}));
      const float lum = std::max(0.0f, 0.5f * centre + 0.125f * corners);
      weights[size_t(y) * w + x] = std::isfinite(lum) ? lum * sin_theta : 0.0f;
    }
  }
  return Distribution2D(weights, w, h);
}

float determinant_sign(const Transform& t) {
  const auto& m = t.matrix().m;
  double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return det < 0 ? -1.0f : 1.0f;
}

float triangle_area(Vec3f a, Vec3f b, Vec3f c) { return 0.5f * length(cross(b - a, c - a)); }

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
  std::vector<Envmap> previous = std::move(envmaps_);
  envmaps_.assign(scene_.emitters.size(), Envmap());
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
          ShapeState::EmitterTriangle& tri = s.emitter_triangles[t];
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

bool FrameScene::intersect(const Ray& ray, SurfaceInteraction* si) const {
  RayHit hit;
  if (!accel_->intersect(ray.o, ray.d, ray.tmin, ray.tmax, &hit)) return false;
  interaction(ray, hit, si);
  return true;
}

void FrameScene::interaction(const Ray& ray, const RayHit& hit, SurfaceInteraction* si) const {
  const Shape& shape = scene_.shapes[size_t(hit.id)];
  const ShapeState& s = shapes_[size_t(hit.id)];
  si->t = hit.t;
  si->shape = hit.id;
  si->prim = hit.prim;
  Vec3f ns;
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
  }
  if (shape.flip_normals) {
    si->n = -si->n;
    ns = -ns;
  }
  si->sh_frame = Frame(ns);
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

EmitterSample FrameScene::sample_emitter_direction(const SurfaceInteraction& ref, float u_select, Vec2f u) const {
  EmitterSample es;
  size_t count = scene_.emitters.size();
  if (count == 0) return es;
  // Uniform emitter selection, as Mitsuba 3 does (keeps noise comparable).
  float scaled = u_select * float(count);
  size_t index = std::min(size_t(scaled), count - 1);
  float select_pdf = 1.0f / float(count);
  const Emitter& em = scene_.emitters[index];
  es.emitter = int(index);

  switch (em.type) {
    case EmitterType::kArea: {
      const ShapeState& s = shapes_[size_t(em.shape)];
      const Shape& shape = scene_.shapes[size_t(em.shape)];
      Vec3f p, n;
      float pdf_solid_angle = 0.0f;
      bool area_measure = false;  // p was sampled by area: convert the pdf below
      if (shape.type == ShapeType::kSphere) {
        Vec3f dc = s.center - ref.p;
        float dc2 = length_squared(dc);
        float r2 = s.radius * s.radius;
        if (dc2 > r2 * (1.0f + 1e-5f)) {
          // Outside: sample the cone of directions the sphere subtends and
          // place the point on the sphere from the cone angles (pbrt-v4's
          // construction; sphere_point_in_cone). Intersecting the sampled ray
          // with the sphere instead cancels catastrophically in float for a
          // light 1e-3 of its distance across and put points on the far side
          // (back-facing: zero radiance, a -0.2 % bias; docs/stability.md).
          // The pdf is formed in double from (radius, distance) alone, exactly
          // as pdf_shape_direction forms it, so that MIS sees equal pdfs; it
          // is off the sample's dependency chain.
          const SphereConePoint c = sphere_point_in_cone(r2 / dc2, u.y);
          // The azimuth needs no care: an error of 1e-7 rad moves the point by 1e-7 radii.
          const SinCos phi = sincos_turns(u.x);
          const Frame frame(dc * (1.0f / std::sqrt(dc2)));  // z towards the centre
          // Unit up to rounding (an orthonormal frame and a unit vector): no normalisation.
          n = frame.to_world(Vec3f(-c.sin_c * phi.cos, -c.sin_c * phi.sin, -c.cos_c));
          p = s.center + n * s.radius;
          pdf_solid_angle = sphere_cone_pdf(double(dc2), double(s.radius) * double(s.radius));
        } else {
          // Inside (or on) the sphere: uniform area sampling.
          n = square_to_uniform_sphere(u);
          p = s.center + n * s.radius;
          area_measure = true;
        }
        if (shape.flip_normals) n = -n;
      } else {
        float u_tri;
        const size_t t = s.triangle_areas.sample(u.x, &u_tri);
        const ShapeState::EmitterTriangle& tri = s.emitter_triangles[t];
        Vec2f b = square_to_uniform_triangle({u_tri, u.y});
        p = tri.p0 * (1.0f - b.x - b.y) + tri.p1 * b.x + tri.p2 * b.y;
        n = tri.n;
        if (!tri.face_normal) {
          // tri.n has flip_normals applied; interpolated_normal() takes and
          // returns normals before it (its fallback is the face normal).
          const Vec3f face_n = shape.flip_normals ? -tri.n : tri.n;
          n = interpolated_normal(s, uint32_t(t), b.x, b.y, face_n);
          if (shape.flip_normals) n = -n;
        }
        area_measure = true;
      }
      Vec3f d = p - ref.p;
      float dist2 = length_squared(d);
      float dist = std::sqrt(dist2);
      if (area_measure) {
        // Area to solid angle: dist^2 / (area cos_l) with cos_l = |d.n| / dist,
        // grouped so that no extra division or overflow enters.
        float abs_dn = std::abs(dot(d, n));
        pdf_solid_angle = abs_dn > 0 ? dist2 * (dist / (s.area * abs_dn)) : 0.0f;
      }
      if (!(dist > 0) || !(pdf_solid_angle > 0) || !std::isfinite(pdf_solid_angle)) return es;
      es.d = d * (1.0f / dist);
      es.dist = dist;
      es.pdf = pdf_solid_angle * select_pdf;
      // One-sided: emits only on the side its normal faces.
      if (dot(n, es.d) < 0) es.weight = em.radiance / es.pdf;
      return es;
    }
    case EmitterType::kPoint:
    case EmitterType::kSpot: {
      Vec3f pos = em.to_world.point(Vec3f(0.0f));
      Vec3f d = pos - ref.p;
      float dist2 = length_squared(d);
      if (!(dist2 > 0)) return es;
      es.dist = std::sqrt(dist2);
      es.d = d / es.dist;
      es.delta = true;
      es.pdf = select_pdf;
      Rgb intensity = em.intensity;
      if (em.type == EmitterType::kSpot) {
        Vec3f local = normalize(em.to_world.inverse().vector(-es.d));
        float cos_theta = local.z;
        float cos_cutoff = std::cos(radians(em.cutoff_angle));
        float cos_beam = std::cos(radians(em.beam_width));
        if (cos_theta <= cos_cutoff) return es;
        if (cos_theta < cos_beam) {
          // Mitsuba's spot: linear falloff in angle between beam_width and cutoff.
          float falloff = (radians(em.cutoff_angle) - std::acos(cos_theta)) /
                          (radians(em.cutoff_angle) - radians(em.beam_width));
          intensity = intensity * std::clamp(falloff, 0.0f, 1.0f);
        }
      }
      es.weight = intensity / (dist2 * select_pdf);
      return es;
    }
    case EmitterType::kDirectional: {
      Vec3f dir = normalize(em.to_world.vector({0, 0, 1}));
      es.d = -dir;
      es.dist = kInfinity;
      es.delta = true;
      es.pdf = select_pdf;
      es.weight = em.irradiance / select_pdf;
      return es;
    }
    case EmitterType::kConstant: {
      es.d = square_to_uniform_sphere(u);
      es.dist = kInfinity;
      es.pdf = kInvFourPi * select_pdf;
      es.weight = em.radiance / es.pdf;
      return es;
    }
    case EmitterType::kEnvmap: {
      const Envmap& env = envmaps_[index];
      if (env.distribution.empty()) return es;
      float pdf_uv;
      Vec2f uv = env.distribution.sample(u, &pdf_uv);
      float sin_theta;
      Vec3f local = uv_to_direction(uv, &sin_theta);
      if (!(sin_theta > 1e-7f) || !(pdf_uv > 0)) return es;
      es.d = normalize(em.to_world.vector(local));
      es.dist = kInfinity;
      es.pdf = pdf_uv / (2.0f * kPi * kPi * sin_theta) * select_pdf;
      // The radiance at the sampled uv itself (no round trip through the
      // direction: two inverse trigonometric functions fewer).
      es.weight = envmap_lookup(*em.envmap, uv) * em.scale / es.pdf;
      return es;
    }
  }
  return es;
}

Rgb FrameScene::eval_envmap(const Emitter& em, const Envmap& env, Vec3f d) const {
  Vec3f local = normalize(env.to_local.vector(d));
  return envmap_lookup(*em.envmap, direction_to_uv(local)) * em.scale;
}

float FrameScene::pdf_shape_direction(const ShapeState& s, Vec3f ref_p, const SurfaceInteraction& hit) const {
  const Shape& shape = scene_.shapes[size_t(hit.shape)];
  if (shape.type == ShapeType::kSphere) {
    Vec3f dc = s.center - ref_p;
    float dc2 = length_squared(dc), r2 = s.radius * s.radius;
    if (dc2 > r2 * (1.0f + 1e-5f)) {
      return sphere_cone_pdf(double(dc2), double(s.radius) * double(s.radius));
    }
  }
  Vec3f d = hit.p - ref_p;
  float dist2 = length_squared(d);
  float cos_l = std::abs(dot(d, hit.sh_frame.n)) / std::sqrt(dist2);
  return cos_l > 0 ? dist2 / (s.area * cos_l) : 0.0f;
}

float FrameScene::pdf_emitter_direction(Vec3f ref_p, const SurfaceInteraction& hit) const {
  int e = emitter_of_shape(hit.shape);
  if (e < 0) return 0.0f;
  return pdf_shape_direction(shapes_[size_t(hit.shape)], ref_p, hit) / float(scene_.emitters.size());
}

// Solid-angle density of an envmap sample at `local` (the envmap's frame), uv
// its texture position; without emitter selection.
float FrameScene::envmap_direction_pdf(const Envmap& env, Vec3f local, Vec2f uv) const {
  const float sin_theta = std::sqrt(std::max(local.x * local.x + local.z * local.z, 1e-14f));
  return env.distribution.pdf(uv) / (2.0f * kPi * kPi * sin_theta);
}

float FrameScene::pdf_environment_direction(Vec3f d) const {
  if (environment_ < 0) return 0.0f;
  const Emitter& em = scene_.emitters[size_t(environment_)];
  const float select_pdf = 1.0f / float(scene_.emitters.size());
  if (em.type == EmitterType::kConstant) return kInvFourPi * select_pdf;
  const Envmap& env = envmaps_[size_t(environment_)];
  const Vec3f local = normalize(env.to_local.vector(d));
  return envmap_direction_pdf(env, local, direction_to_uv(local)) * select_pdf;
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
  const Envmap& env = envmaps_[size_t(environment_)];
  const Vec3f local = normalize(env.to_local.vector(d));
  const Vec2f uv = direction_to_uv(local);
  out.radiance = envmap_lookup(*em.envmap, uv) * em.scale;
  out.pdf = envmap_direction_pdf(env, local, uv) * select_pdf;
  return out;
}

void FrameScene::prefetch_emitter_sample(float u_select, Vec2f u) const {
  const size_t count = scene_.emitters.size();
  if (count == 0) return;
  const size_t index = std::min(size_t(u_select * float(count)), count - 1);
  if (scene_.emitters[index].type != EmitterType::kEnvmap) return;
  const Envmap& env = envmaps_[index];
  const Vec2f uv = env.distribution.prefetch_sample(u);
  const BilinearTexels t = envmap_texels(*env.image, uv);
  env.image->prefetch_rgb(t.x0, t.y0);
  env.image->prefetch_rgb(t.x0, t.y1);
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
