#include "core/render/vector_scene.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

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

// What the kernel can do with hits on shape i: kShapeConductor for a rough
// Beckmann conductor sampled by visible normals, kShapePlastic for smooth
// plastic with constant reflectances, 0 for a diffuse BSDF (all on triangle
// meshes), kShapeScalar for anything else.
uint32_t shading_kind(const Scene& scene, size_t i) {
  const Shape& shape = scene.shapes[i];
  if (shape.type != ShapeType::kMesh) return kShapeScalar;
  const Bsdf& bsdf = scene.bsdfs[size_t(shape.bsdf)];
  if (bsdf.type == BsdfType::kDiffuse)
    return bsdf.reflectance.is_constant() && !is_finite(bsdf.reflectance.value) ? kShapeScalar : 0u;
  // The kernel builds its frames from the normal alone (Frame(n)), which an
  // anisotropic BSDF cannot take (FrameScene::interaction).
  if (bsdf.type == BsdfType::kRoughConductor && bsdf.distribution == MicrofacetType::kBeckmann && !bsdf.is_anisotropic() &&
      bsdf.sample_visible && bsdf.specular_reflectance.is_constant() && is_finite(bsdf.specular_reflectance.value) &&
      is_finite(bsdf.eta) && is_finite(bsdf.k))
    return kShapeConductor;
  if (bsdf.type == BsdfType::kPlastic && bsdf.reflectance.is_constant() && is_finite(bsdf.reflectance.value) &&
      bsdf.specular_reflectance.is_constant() && is_finite(bsdf.specular_reflectance.value))
    return kShapePlastic;
  return kShapeScalar;
}

// kShapeReflectsNothing where shape i's BSDF is diffuse with a constant
// reflectance of exactly zero (twosided or not), else 0.
uint32_t reflects_nothing(const Scene& scene, size_t i) {
  const Bsdf& bsdf = scene.bsdfs[size_t(scene.shapes[i].bsdf)];
  const bool black =
      bsdf.type == BsdfType::kDiffuse && bsdf.reflectance.is_constant() && bsdf.reflectance.value.is_black();
  return black ? kShapeReflectsNothing : 0u;
}

// FrameScene::sample_emitter_direction for the kernel (SampleEmitterFn). Only
// the reference point of the interaction is read.
void sample_emitter_lane(const void* scene, const float p[3], float u_select, float ux, float uy,
                         EmitterSampleLane* out) {
  SurfaceInteraction ref;
  ref.p = Vec3f(p[0], p[1], p[2]);
  const EmitterSample es = static_cast<const FrameScene*>(scene)->sample_emitter_direction(ref, u_select, {ux, uy});
  put3(out->d, es.d);
  out->dist = es.dist;
  out->pdf = es.pdf;
  put3(out->weight, es.weight);
  out->delta = es.delta ? -1 : 0;
}

}  // namespace

std::unique_ptr<VectorScene> VectorScene::build(const FrameScene& fs, std::string* why_not) {
  const Scene& scene = fs.scene_;
  auto fail = [why_not](std::string reason) {
    *why_not = std::move(reason);
    return std::unique_ptr<VectorScene>();
  };
  if (scene.emitters.empty()) return fail("the scene has no emitter");
  // Paths through thin dielectrics carry PathState::scattered, which the
  // lanes do not hold.
  if (scene.defaults.hide_emitters)
    for (const Bsdf& b : scene.bsdfs)
      if (b.type == BsdfType::kThinDielectric)
        return fail("the scene hides its emitters and has a thin dielectric");
  size_t triangle_count = 0, vector_shapes = 0;
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    if (shading_kind(scene, i) == kShapeScalar) continue;
    ++vector_shapes;
    triangle_count += fs.shapes_[i].mesh->triangle_count();
  }
  if (vector_shapes == 0)
    return fail("no shape is a triangle mesh with a diffuse, a rough Beckmann conductor or a smooth plastic BSDF");
  if (triangle_count > kMaxTriangles)
    return fail("the scene has " + std::to_string(triangle_count) + " triangles (records are built for at most " +
                std::to_string(kMaxTriangles) + ")");

  std::unique_ptr<VectorScene> ds(new VectorScene());
  ds->triangles_.resize(triangle_count);
  ds->shape_first_.assign(scene.shapes.size(), 0);
  ds->shape_flags_.assign(scene.shapes.size(), 0);
  ds->shape_texture_.assign(scene.shapes.size(), nullptr);
  ds->shape_checkerboard_.assign(scene.shapes.size(), CheckerboardRecord{});
  ds->shape_conductor_.assign(scene.shapes.size(), ConductorRecord{});
  ds->shape_plastic_.assign(scene.shapes.size(), PlasticRecord{});
  uint32_t first = 0;
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    const uint32_t kind = shading_kind(scene, i);
    if (kind == kShapeScalar) {
      ds->shape_flags_[i] = kShapeScalar | reflects_nothing(scene, i);
      continue;
    }
    ds->shape_first_[i] = first;
    first += uint32_t(fs.shapes_[i].mesh->triangle_count());
    const Bsdf& bsdf = scene.bsdfs[size_t(scene.shapes[i].bsdf)];
    const bool textured = kind == 0 && !bsdf.reflectance.is_constant();
    ds->shape_flags_[i] = kind | (bsdf.two_sided ? kShapeTwoSided : 0u) | (textured ? kShapeTextured : 0u) |
                          (fs.shapes_[i].mesh->uvs.empty() ? 0u : kShapeHasUvs) | reflects_nothing(scene, i);
    ds->shape_texture_[i] = textured ? &bsdf.reflectance : nullptr;
    if (textured && bsdf.reflectance.type == TextureType::kCheckerboard) {
      const Texture& t = bsdf.reflectance;
      CheckerboardRecord& r = ds->shape_checkerboard_[i];
      r.a = t.to_uv.a, r.b = t.to_uv.b, r.c = t.to_uv.c, r.d = t.to_uv.d, r.e = t.to_uv.e, r.f = t.to_uv.f;
      put3(r.color0, t.color0);
      put3(r.color1, t.color1);
      ds->shape_flags_[i] |= kShapeCheckerboard;
    }
    if (kind == kShapeConductor) {
      // As MicrofacetDistribution's constructor clamps them.
      ConductorRecord& c = ds->shape_conductor_[i];
      c.alpha_u = std::max(bsdf.alpha_u, 1e-4f);
      c.alpha_v = std::max(bsdf.alpha_v, 1e-4f);
      put3(c.eta, bsdf.eta);
      put3(c.k, bsdf.k);
      put3(c.specular, bsdf.specular_reflectance.value);
    }
    if (kind == kShapePlastic) {
      // As plastic.cpp computes them per call.
      PlasticRecord& pr = ds->shape_plastic_[i];
      pr.eta = bsdf.int_ior / bsdf.ext_ior;
      pr.rcp_eta = 1.0f / pr.eta;
      pr.inv_eta2 = 1.0f / (pr.eta * pr.eta);
      pr.specular_weight = bsdf.specular_sampling_weight;
      put3(pr.specular, bsdf.specular_reflectance.value);
    }
    if (fs.shapes_[i].instanced) ds->animated_shapes_.push_back(i);
    if (!ds->bake_shape(fs, i, why_not)) return nullptr;
  }
  ds->frame_scene_ = &fs;
  ds->bake_emitters(fs);
  ds->update_view();
  return ds;
}

bool VectorScene::refresh(const FrameScene& fs, std::string* why_not) {
  for (size_t i : animated_shapes_)
    if (!bake_shape(fs, i, why_not)) return false;
  bake_emitters(fs);
  update_view();
  return true;
}

bool VectorScene::bake_shape(const FrameScene& fs, size_t i, std::string* why_not) {
  const Scene& scene = fs.scene_;
  const Shape& shape = scene.shapes[i];
  const FrameScene::ShapeState& s = fs.shapes_[i];
  // World space for a static shape; object space (placed by to_world) for an animated one.
  const TriangleMesh& m = *s.mesh;
  const Bsdf& bsdf = scene.bsdfs[size_t(shape.bsdf)];
  const bool textured = (shape_flags_[i] & kShapeTextured) != 0;
  // A diffuse triangle's record holds its constant reflectance, a plastic
  // one's its diffuse base; a conductor's none (ConductorRecord has its parameters).
  Rgb albedo(0.0f);
  if (shape_flags_[i] & kShapePlastic) albedo = plastic_diffuse_base(bsdf, bsdf.reflectance.value, bsdf.fdr_int);
  else if (!textured && !(shape_flags_[i] & kShapeConductor)) albedo = bsdf.reflectance.value;
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
    VectorTriangleRecord& r = triangles_[shape_first_[i] + t];
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

static_assert(sizeof(AliasSlotRecord) == sizeof(AliasSlot) && offsetof(AliasSlotRecord, q) == offsetof(AliasSlot, q) &&
                  offsetof(AliasSlotRecord, alias) == offsetof(AliasSlot, alias) &&
                  offsetof(AliasSlotRecord, pmf) == offsetof(AliasSlot, pmf) &&
                  offsetof(AliasSlotRecord, alias_pmf) == offsetof(AliasSlot, alias_pmf),
              "AliasSlotRecord mirrors AliasSlot");

void VectorScene::bake_emitters(const FrameScene& fs) {
  const Scene& scene = fs.scene_;
  // The environment map's tables and frame (its to_world may be animated).
  has_envmap_ = false;
  if (fs.environment_ >= 0 && scene.emitters[size_t(fs.environment_)].type == EmitterType::kEnvmap) {
    const Emitter& em = scene.emitters[size_t(fs.environment_)];
    const EnvmapTables& env = fs.envmaps_[size_t(fs.environment_)];
    if (!env.distribution.empty()) {
      has_envmap_ = true;
      const Distribution2D& dist = env.distribution;
      envmap_.marginal = reinterpret_cast<const AliasSlotRecord*>(dist.marginal_slots());
      envmap_.rows = reinterpret_cast<const AliasSlotRecord*>(dist.row_slots());
      envmap_.width = dist.width();
      envmap_.height = dist.height();
      envmap_.texels = env.image->data().data();
      envmap_.image_width = env.image->width();
      envmap_.image_height = env.image->height();
      envmap_.channels = env.image->channels();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          envmap_.to_world[r][c] = em.to_world.matrix().m[size_t(r)][size_t(c)];
          envmap_.to_local[r][c] = env.to_local.matrix().m[size_t(r)][size_t(c)];
        }
      envmap_.scale = em.scale;
      envmap_.emitter = uint32_t(fs.environment_);
    }
  }
  emitter_triangles_.clear();
  emitter_spheres_.clear();
  emitter_first_.assign(scene.emitters.size(), 0);
  emitter_choice_.assign(scene.emitters.size(), nullptr);
  for (size_t e = 0; e < scene.emitters.size(); ++e) {
    const Emitter& em = scene.emitters[e];
    if (em.type != EmitterType::kArea || scene.shapes[size_t(em.shape)].type != ShapeType::kSphere) continue;
    if (emitter_spheres_.empty()) emitter_spheres_.resize(scene.emitters.size(), SphereEmitterRecord{});
    const FrameScene::ShapeState& s = fs.shapes_[size_t(em.shape)];
    SphereEmitterRecord& r = emitter_spheres_[e];
    put3(r.center, s.center);
    r.radius = s.radius;
    put3(r.radiance, em.radiance);
    r.flip = scene.shapes[size_t(em.shape)].flip_normals ? -1.0f : 1.0f;
  }
  // Records only where every emitter is an area emitter on a flat-shaded
  // mesh; otherwise the kernel asks FrameScene lane by lane.
  for (const Emitter& em : scene.emitters) {
    if (em.type != EmitterType::kArea || scene.shapes[size_t(em.shape)].type != ShapeType::kMesh) return;
    for (const EmitterTriangle& tri : fs.shapes_[size_t(em.shape)].emitter_triangles)
      if (!tri.face_normal) return;
  }
  for (size_t e = 0; e < scene.emitters.size(); ++e) {
    const Emitter& em = scene.emitters[e];
    const FrameScene::ShapeState& s = fs.shapes_[size_t(em.shape)];
    emitter_first_[e] = uint32_t(emitter_triangles_.size());
    emitter_choice_[e] = &s.triangle_areas;
    for (const EmitterTriangle& tri : s.emitter_triangles) {
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
}

void VectorScene::update_view() {
  view_.triangles = triangles_.data();
  view_.shading = shading_.empty() ? nullptr : shading_.data();
  view_.shape_first = shape_first_.data();
  view_.shape_flags = shape_flags_.data();
  view_.shape_texture = shape_texture_.data();
  view_.shape_checkerboard = shape_checkerboard_.data();
  view_.shape_conductor = shape_conductor_.data();
  view_.shape_plastic = shape_plastic_.data();
  view_.emitter_triangles = emitter_triangles_.empty() ? nullptr : emitter_triangles_.data();
  view_.sample_emitter = sample_emitter_lane;
  view_.emitter_spheres = emitter_spheres_.empty() ? nullptr : emitter_spheres_.data();
  view_.envmap = has_envmap_ ? &envmap_ : nullptr;
  view_.frame_scene = frame_scene_;
  view_.emitter_first = emitter_first_.data();
  view_.emitter_choice = emitter_choice_.data();
  view_.emitter_count = uint32_t(emitter_first_.size());
  // As FrameScene::sample_emitter_direction computes it.
  view_.select_pdf = 1.0f / float(emitter_first_.size());
}

size_t VectorScene::memory_bytes() const {
  return triangles_.size() * sizeof(VectorTriangleRecord) + shading_.size() * sizeof(ShadingRecord) +
         emitter_triangles_.size() * sizeof(EmitterTriangleRecord) +
         shape_conductor_.size() * sizeof(ConductorRecord) +
         shape_plastic_.size() * sizeof(PlasticRecord) +
         emitter_spheres_.size() * sizeof(SphereEmitterRecord) +
         (shape_first_.size() + shape_flags_.size() + emitter_first_.size()) * sizeof(uint32_t) +
         shape_texture_.size() * sizeof(const Texture*) +
         shape_checkerboard_.size() * sizeof(CheckerboardRecord) +
         emitter_choice_.size() * sizeof(const Distribution1D*);
}

}  // namespace gdvr
