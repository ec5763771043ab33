#include "core/render/diffuse_scene.h"

#include <cmath>

#include "core/render/frame_scene.h"

namespace gdvr {
namespace {

void put3(float out[3], Vec3f v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

void put3(float out[3], Rgb c) {
  out[0] = c.r;
  out[1] = c.g;
  out[2] = c.b;
}

std::string shape_name(const Scene& scene, size_t i) {
  const std::string& id = scene.shapes[i].id;
  return "shape " + std::to_string(i) + (id.empty() ? "" : " ('" + id + "')");
}

}  // namespace

std::unique_ptr<DiffuseScene> DiffuseScene::build(const FrameScene& fs, std::string* why_not) {
  const Scene& scene = fs.scene_;
  auto fail = [why_not](std::string reason) {
    *why_not = std::move(reason);
    return std::unique_ptr<DiffuseScene>();
  };
  if (scene.emitters.empty()) return fail("the scene has no emitter");
  for (size_t e = 0; e < scene.emitters.size(); ++e)
    if (scene.emitters[e].type != EmitterType::kArea)
      return fail("emitter " + std::to_string(e) + " is not an area emitter");
  for (size_t e = 0; e < scene.emitters.size(); ++e)
    for (const FrameScene::ShapeState::EmitterTriangle& tri : fs.shapes_[size_t(scene.emitters[e].shape)].emitter_triangles)
      if (!tri.face_normal) return fail("emitter " + std::to_string(e) + "'s shape interpolates vertex normals");
  size_t triangle_count = 0;
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    const Shape& shape = scene.shapes[i];
    const FrameScene::ShapeState& s = fs.shapes_[i];
    if (shape.type != ShapeType::kMesh) return fail(shape_name(scene, i) + " is not a triangle mesh");
    if (s.instanced) return fail(shape_name(scene, i) + " is animated");
    const Bsdf& bsdf = scene.bsdfs[size_t(shape.bsdf)];
    if (bsdf.type != BsdfType::kDiffuse || bsdf.two_sided || !bsdf.reflectance.is_constant() ||
        !is_finite(bsdf.reflectance.value))
      return fail(shape_name(scene, i) + "'s BSDF is not a one-sided diffuse one of constant reflectance");
    triangle_count += s.mesh->triangle_count();
  }
  if (triangle_count > kMaxTriangles)
    return fail("the scene has " + std::to_string(triangle_count) + " triangles (records are built for at most " +
                std::to_string(kMaxTriangles) + ")");

  std::unique_ptr<DiffuseScene> ds(new DiffuseScene());
  ds->triangles_.reserve(triangle_count);
  ds->shape_first_.resize(scene.shapes.size());
  bool any_smooth = false;
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    const Shape& shape = scene.shapes[i];
    const FrameScene::ShapeState& s = fs.shapes_[i];
    const TriangleMesh& m = *s.mesh;  // world space: the shape is static
    const Rgb albedo = scene.bsdfs[size_t(shape.bsdf)].reflectance.value;
    ds->shape_first_[i] = uint32_t(ds->triangles_.size());
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      DiffuseTriangleRecord r;
      put3(r.p0, m.positions[m.indices[3 * t]]);
      put3(r.p1, m.positions[m.indices[3 * t + 1]]);
      put3(r.p2, m.positions[m.indices[3 * t + 2]]);
      const Vec3f n = FrameScene::world_face_normal(s, t);  // what interaction() reads
      put3(r.n, shape.flip_normals ? -n : n);
      put3(r.albedo, albedo);
      const bool smooth = !FrameScene::shades_with_face_normal(s, t);
      r.offset_floor = smooth ? -s.offset_floors[t] : s.offset_floors[t];
      any_smooth |= smooth;
      ds->triangles_.push_back(r);
    }
  }
  if (any_smooth) {
    // OBJ meshes without normals get smooth vertex normals, as in Mitsuba, so
    // a non-planar quad (cbox's red wall) shades with them.
    ds->smooth_normals_.resize(triangle_count);
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
      const FrameScene::ShapeState& s = fs.shapes_[i];
      const TriangleMesh& m = *s.mesh;
      for (size_t t = 0; t < m.triangle_count(); ++t) {
        if (FrameScene::shades_with_face_normal(s, t)) continue;
        SmoothNormalsRecord& r = ds->smooth_normals_[ds->shape_first_[i] + t];
        put3(r.n0, m.normals[m.indices[3 * t]]);
        put3(r.n1, m.normals[m.indices[3 * t + 1]]);
        put3(r.n2, m.normals[m.indices[3 * t + 2]]);
        r.flip = scene.shapes[i].flip_normals ? -1.0f : 1.0f;
      }
    }
  }
  ds->refresh_emitters(fs);
  return ds;
}

void DiffuseScene::refresh_emitters(const FrameScene& fs) {
  const Scene& scene = fs.scene_;
  emitter_triangles_.clear();
  emitter_first_.assign(scene.emitters.size(), 0);
  emitter_choice_.assign(scene.emitters.size(), nullptr);
  for (size_t e = 0; e < scene.emitters.size(); ++e) {
    const Emitter& em = scene.emitters[e];
    const FrameScene::ShapeState& s = fs.shapes_[size_t(em.shape)];
    emitter_first_[e] = uint32_t(emitter_triangles_.size());
    emitter_choice_[e] = &s.triangle_areas;
    for (const FrameScene::ShapeState::EmitterTriangle& tri : s.emitter_triangles) {
      EmitterTriangleRecord r;
      put3(r.p0, tri.p0);
      put3(r.p1, tri.p1);
      put3(r.p2, tri.p2);
      put3(r.n, tri.n);  // flip_normals applied; flat (build() checked every triangle)
      put3(r.radiance, em.radiance);
      r.area = s.area;
      emitter_triangles_.push_back(r);
    }
  }
  update_view();
}

void DiffuseScene::update_view() {
  view_.triangles = triangles_.data();
  view_.smooth_normals = smooth_normals_.empty() ? nullptr : smooth_normals_.data();
  view_.shape_first = shape_first_.data();
  view_.emitter_triangles = emitter_triangles_.data();
  view_.emitter_first = emitter_first_.data();
  view_.emitter_choice = emitter_choice_.data();
  view_.emitter_count = uint32_t(emitter_first_.size());
  // As FrameScene::sample_emitter_direction computes it.
  view_.select_pdf = 1.0f / float(emitter_first_.size());
}

size_t DiffuseScene::memory_bytes() const {
  return triangles_.size() * sizeof(DiffuseTriangleRecord) + smooth_normals_.size() * sizeof(SmoothNormalsRecord) +
         emitter_triangles_.size() * sizeof(EmitterTriangleRecord) +
         (shape_first_.size() + emitter_first_.size()) * sizeof(uint32_t) +
         emitter_choice_.size() * sizeof(const Distribution1D*);
}

}  // namespace gdvr
