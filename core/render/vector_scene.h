// A scene laid out for the vector path batch's kernel (vector_batch.h):
// one 64-byte record per triangle of every mesh whose BSDF the kernel
// shades (diffuse, one- or two-sided, constant or textured reflectance; rough
// Beckmann conductors sampled by visible normals and smooth plastic with
// constant reflectances, with their parameters per shape), instead of the
// index buffer, three corners and four per-triangle tables that a vertex
// otherwise reads. Other shapes are flagged for the scalar stages
// (kShapeScalar). Emitters: triangle records where every emitter is a
// flat-shaded area light on a mesh; sphere records for sphere area lights;
// the environment map's tables (FrameScene's own); FrameScene's sampling for
// the rest.
//
// FrameScene builds it where the scene allows (an emitter and at least one
// shape the kernel shades) and says why not elsewhere; everything else
// keeps the general path tracer.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/render/vector_batch_state.h"

namespace gdvr {

class FrameScene;

class VectorScene {
 public:
  // The records of `scene`, or null with `why_not` naming the first thing
  // the scene has that they cannot hold.
  static std::unique_ptr<VectorScene> build(const FrameScene& scene, std::string* why_not);
  // After FrameScene::update: re-bakes the animated shapes' records at their
  // new place and re-reads the emitters. False (and `why_not`) where the
  // scene no longer fits (an animated shape's mirroring transform made it
  // interpolate vertex normals); the records must then be dropped.
  bool refresh(const FrameScene& scene, std::string* why_not);

  const VectorSceneView& view() const { return view_; }
  size_t memory_bytes() const;

  // Beyond this many triangles the records (64 or 128 bytes each) are not built.
  static constexpr size_t kMaxTriangles = size_t(1) << 20;

 private:
  VectorScene() = default;
  // Shape i's triangle records as interaction() would shade its hits now.
  bool bake_shape(const FrameScene& scene, size_t i, std::string* why_not);
  void bake_emitters(const FrameScene& scene);
  void update_view();

  std::vector<VectorTriangleRecord> triangles_;
  std::vector<ShadingRecord> shading_;  // parallel to triangles_, or empty if all are flat and untextured
  std::vector<uint32_t> shape_first_;
  std::vector<uint32_t> shape_flags_;
  std::vector<const Texture*> shape_texture_;
  std::vector<CheckerboardRecord> shape_checkerboard_;
  std::vector<ConductorRecord> shape_conductor_;
  std::vector<PlasticRecord> shape_plastic_;
  std::vector<size_t> animated_shapes_;
  std::vector<EmitterTriangleRecord> emitter_triangles_;
  std::vector<SphereEmitterRecord> emitter_spheres_;  // empty without sphere emitters
  EnvmapRecord envmap_{};
  bool has_envmap_ = false;
  std::vector<uint32_t> emitter_first_;
  std::vector<const Distribution1D*> emitter_choice_;
  const FrameScene* frame_scene_ = nullptr;  // owns these records
  VectorSceneView view_;
};

}  // namespace gdvr
