// The scene as loaded: shapes (object space + to_world), BSDFs, emitters, the
// camera and the render settings the file asked for. Plain data; the
// accelerator and the integrators build their per-frame state from it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/bsdf/bsdf.h"
#include "core/emitter/emitter.h"
#include "core/math/transform.h"

namespace gdvr {

struct TriangleMesh {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;   // per vertex, optional (empty: face normals)
  std::vector<Vec2f> uvs;       // per vertex, optional
  std::vector<uint32_t> indices;  // 3 per triangle
  size_t triangle_count() const { return indices.size() / 3; }
};

enum class ShapeType {
  kMesh,    // obj, ply, serialized, and the tessellated rectangle, cube, disk
  kSphere,  // analytic unit sphere at the origin; to_world carries center and radius
};

struct Shape {
  std::string id;  // may be empty; animation tracks address shapes by id
  ShapeType type = ShapeType::kMesh;
  std::shared_ptr<const TriangleMesh> mesh;  // object space
  Transform to_world;
  bool flip_normals = false;
  bool face_normals = false;  // ignore vertex normals
  int bsdf = -1;              // index into Scene::bsdfs (always valid after loading)
  int emitter = -1;           // area emitter index into Scene::emitters, or -1
};

enum class FovAxis { kX, kY, kDiagonal, kSmaller, kLarger };

struct Camera {
  std::string id;
  Transform to_world;  // Mitsuba convention: looks along +z, +y up
  float fov = 39.3077f;
  FovAxis fov_axis = FovAxis::kX;
  float near_clip = 0.01f, far_clip = 10000.0f;
};

// Where a render default was set, so that a refusal (the server's resource
// limits) can say why a value is what it is rather than only what it is.
struct SettingOrigin {
  std::string where;                // "scene.xml:12"; empty: gdvr's built-in default
  std::vector<std::string> params;  // <default> parameters substituted into it ("res")
};

// The largest film side a scene file or a job may ask for. It bounds what one
// request can make a render node allocate: a 16384² RGB float layer is 3 GiB,
// and a gradient-domain frame holds a dozen layers.
inline constexpr int kMaxFilmResolution = 16384;

struct RenderDefaults {
  int width = 768, height = 576;  // hdrfilm
  int spp = 4;                    // sampler sample_count
  SettingOrigin width_origin, height_origin, spp_origin;
  int max_depth = -1;             // Mitsuba path: 1 = emitters seen directly, -1 unbounded
  int rr_depth = 5;               // Russian roulette from this depth on
  bool hide_emitters = false;
};

struct Scene {
  std::string source;  // file it came from (for messages)
  std::vector<Shape> shapes;
  std::vector<Bsdf> bsdfs;
  std::vector<Emitter> emitters;
  Camera camera;
  RenderDefaults defaults;
  // Problems the loader repaired or approximated (dropped degenerate triangles,
  // recomputed NaN normals, a Gaussian rfilter rendered as box, ...), one line each.
  std::vector<std::string> warnings;
};

}  // namespace gdvr
