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
  size_t triangle_count = 0;
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    const Shape& shape = scene.shapes[i];
    if (shape.type != ShapeType::kMesh) return fail(shape_name(scene, i) + " is not a triangle mesh");
    const Bsdf& bsdf = scene.bsdfs[size_t(shape.bsdf)];
    if (bsdf.type != BsdfType::kDiffuse)
      return fail(shape_name(scene, i) + "'s BSDF is not a diffuse one");
    if (bsdf.reflectance.is_constant() && !is_finite(bsdf.reflectance.value))
      return fail(shape_name(scene, i) + "'s reflectance is not finite");
    triangle_count += fs.shapes_[i].mesh->triangle_count();
  }
  if (triangle_count > kMaxTriangles)
    return fail("the scene has " + std::to_string(triangle_count) + " triangles (records are built for at most " +
                std::to_string(kMaxTriangles) + ")");

  std::unique_ptr<DiffuseScene> ds(new DiffuseScene());
  ds->triangles_.resize(triangle_count);
  ds->shape_first_.resize(scene.shapes.size());
  ds->shape_flags_.resize(scene.shapes.size());
  ds->shape_texture_.resize(scene.shapes.size());
  uint32_t first = 0;
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    ds->shape_first_[i] = first;
    first += uint32_t(fs.shapes_[i].mesh->triangle_count());
    const Bsdf& bsdf = scene.bsdfs[size_t(scene.shapes[i].bsdf)];
    const bool textured = !bsdf.reflectance.is_constant();
    ds->shape_flags_[i] = (bsdf.two_sided ? kShapeTwoSided : 0u) | (textured ? kShapeTextured : 0u) |
                          (fs.shapes_[i].mesh->uvs.empty() ? 0u : kShapeHasUvs);
    ds->shape_texture_[i] = textured ? &bsdf.reflectance : nullptr;
    if (fs.shapes_[i].instanced) ds->animated_shapes_.push_back(i);
    if (!ds->bake_shape(fs, i, why_not)) return nullptr;
  }
  if (!ds->bake_emitters(fs, why_not)) return nullptr;
  ds->update_view();
  return ds;
}

bool DiffuseScene::refresh(const FrameScene& fs, std::string* why_not) {
  for (size_t i : animated_shapes_)
    if (!bake_shape(fs, i, why_not)) return false;
  if (!bake_emitters(fs, why_not)) return false;
  update_view();
  return true;
}

bool DiffuseScene::bake_shape(const FrameScene& fs, size_t i, std::string* why_not) {
  const Scene& scene = fs.scene_;
  const Shape& shape = scene.shapes[i];
  const FrameScene::ShapeState& s = fs.shapes_[i];
  // World space for a static shape; object space (placed by to_world) for an animated one.
  const TriangleMesh& m = *s.mesh;
  const Texture& reflectance = scene.bsdfs[size_t(shape.bsdf)].reflectance;
  const bool textured = !reflectance.is_constant();
  const Rgb albedo = textured ? Rgb(0.0f) : reflectance.value;
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    Vec3f p0 = m.positions[m.indices[3 * t]], p1 = m.positions[m.indices[3 * t + 1]],
          p2 = m.positions[m.indices[3 * t + 2]];
    if (s.instanced) p0 = s.to_world.point(p0), p1 = s.to_world.point(p1), p2 = s.to_world.point(p2);
    // What interaction() computes at a hit on the triangle.
    const Vec3f n = FrameScene::world_face_normal(s, t);
    const float offset_floor = s.instanced ? triangle_offset_floor(p0, p1, p2) : s.offset_floors[t];
    const bool smooth = !FrameScene::shades_with_face_normal(s, t);
    if (smooth && s.instanced) {
      // interaction() transforms the interpolated normal of an animated
      // shape; the kernel interpolates world-space normals only.
      *why_not = "animated " + shape_name(scene, i) + " interpolates vertex normals";
      return false;
    }
    DiffuseTriangleRecord& r = triangles_[shape_first_[i] + t];
    put3(r.p0, p0);
    put3(r.p1, p1);
    put3(r.p2, p2);
    put3(r.n, shape.flip_normals ? -n : n);
    put3(r.albedo, albedo);
    r.offset_floor = smooth ? -offset_floor : offset_floor;
    if (!smooth && !textured) continue;
    // OBJ meshes without normals get smooth vertex normals, as in Mitsuba, so
    // a non-planar quad (cbox's red wall) shades with them.
    if (shading_.empty()) shading_.resize(triangles_.size());
    ShadingRecord& sr = shading_[shape_first_[i] + t];
    if (smooth) {
      put3(sr.n0, m.normals[m.indices[3 * t]]);
      put3(sr.n1, m.normals[m.indices[3 * t + 1]]);
      put3(sr.n2, m.normals[m.indices[3 * t + 2]]);
      sr.flip = shape.flip_normals ? -1.0f : 1.0f;
    }
    if (textured && !m.uvs.empty()) {
      const Vec2f uv0 = m.uvs[m.indices[3 * t]], uv1 = m.uvs[m.indices[3 * t + 1]], uv2 = m.uvs[m.indices[3 * t + 2]];
      sr.uv0[0] = uv0.x, sr.uv0[1] = uv0.y;
      sr.uv1[0] = uv1.x, sr.uv1[1] = uv1.y;
      sr.uv2[0] = uv2.x, sr.uv2[1] = uv2.y;
    }
  }
  return true;
}

bool DiffuseScene::bake_emitters(const FrameScene& fs, std::string* why_not) {
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
      if (!tri.face_normal) {
        *why_not = "emitter " + std::to_string(e) + "'s shape interpolates vertex normals";
        return false;
      }
      EmitterTriangleRecord r;
      put3(r.p0, tri.p0);
      put3(r.p1, tri.p1);
      put3(r.p2, tri.p2);
      put3(r.n, tri.n);  // flip_normals applied
      put3(r.radiance, em.radiance);
      r.area = s.area;
      emitter_triangles_.push_back(r);
    }
  }
  return true;
}

void DiffuseScene::update_view() {
  view_.triangles = triangles_.data();
  view_.shading = shading_.empty() ? nullptr : shading_.data();
  view_.shape_first = shape_first_.data();
  view_.shape_flags = shape_flags_.data();
  view_.shape_texture = shape_texture_.data();
  view_.emitter_triangles = emitter_triangles_.data();
  view_.emitter_first = emitter_first_.data();
  view_.emitter_choice = emitter_choice_.data();
  view_.emitter_count = uint32_t(emitter_first_.size());
  // As FrameScene::sample_emitter_direction computes it.
  view_.select_pdf = 1.0f / float(emitter_first_.size());
}

size_t DiffuseScene::memory_bytes() const {
  return triangles_.size() * sizeof(DiffuseTriangleRecord) + shading_.size() * sizeof(ShadingRecord) +
         emitter_triangles_.size() * sizeof(EmitterTriangleRecord) +
         (shape_first_.size() + shape_flags_.size() + emitter_first_.size()) * sizeof(uint32_t) +
         shape_texture_.size() * sizeof(const Texture*) +
         emitter_choice_.size() * sizeof(const Distribution1D*);
}

}  // namespace gdvr
