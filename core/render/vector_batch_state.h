// What the vector kernel of the vector path batch (vector_batch.h) reads
// and writes: the scene as one 64-byte record per triangle, and a batch of
// paths as struct of arrays (one array per field, a lane per path), so that
// eight paths' fields load as one AVX2 vector.
//
// Plain data only. The kernel (vector_vertex_kernel.inl) is compiled for
// AVX2 and for AVX-512 and runs only where the CPU has them; an inline
// function it shared with the rest of gdvr could be emitted in such a form
// and picked by the linker for callers on any CPU. So nothing here has code,
// and the kernel keeps its own.
#pragma once

#include <cstdint>

namespace gdvr {

class Distribution1D;
struct Texture;

// Paths in a vector batch (== kPathBatch: path_batch.cpp hands its batches over).
constexpr int kVectorBatch = 256;

// A triangle of a mesh whose BSDF the kernel shades, in world space at this frame:
// what a vertex on it reads, in one cache line (with gathers of indices,
// corners, normal, offset floor and reflectance field by field, AVX2 gained
// a fifth less: docs/experiments/README.md).
struct alignas(64) VectorTriangleRecord {
  float p0[3], p1[3], p2[3];  // world-space corners
  float n[3];                 // unit face normal, flip_normals applied
  float albedo[3];            // the diffuse reflectance where it is constant
  // SurfaceInteraction::offset_floor (never negative), its sign bit set where
  // the triangle shades with interpolated vertex normals (ShadingRecord)
  // rather than with its face normal.
  float offset_floor;
};
static_assert(sizeof(VectorTriangleRecord) == 64);

// What a triangle needs beyond its VectorTriangleRecord where it shades
// with interpolated vertex normals or a textured reflectance, at the same
// index: the vertex normals (world space, before flip_normals) and uvs.
struct alignas(64) ShadingRecord {
  float n0[3], n1[3], n2[3];
  float flip;  // -1 with flip_normals, else 1
  float uv0[2], uv1[2], uv2[2];
};
static_assert(sizeof(ShadingRecord) == 64);

// A triangle of an area emitter, with its emitter's radiance and total area.
struct alignas(64) EmitterTriangleRecord {
  float p0[3], p1[3], p2[3];
  float n[3];  // unit face normal, flip_normals applied
  float radiance[3];
  float area;  // the emitter shape's whole area
};
static_assert(sizeof(EmitterTriangleRecord) == 64);

// VectorSceneView::shape_flags: what a shape's hits need beyond its records.
constexpr uint32_t kShapeTwoSided = 1;  // its BSDF is two-sided
constexpr uint32_t kShapeTextured = 2;  // its reflectance is a texture (ShadingRecord has the uvs)
constexpr uint32_t kShapeHasUvs = 4;    // its mesh has uvs (else the barycentrics are the uv, as in interaction())
// Its BSDF is a rough conductor with Beckmann visible-normal sampling
// (ConductorRecord), not a diffuse one.
constexpr uint32_t kShapeConductor = 8;
// The kernel does not shade its hits (a sphere, another BSDF): the driver
// runs the scalar stages for them (vector_batch.cpp), and it has no records.
constexpr uint32_t kShapeScalar = 16;
// Its BSDF reflects nothing (a diffuse one of constant reflectance 0, as
// veach-mis's sphere lights have): a path that hits it takes the emission
// and ends there, as the scalar stages would end it (they sample an emitter
// and a direction for nothing), without shading the vertex.
constexpr uint32_t kShapeReflectsNothing = 32;
// Its BSDF is smooth plastic with constant reflectances (PlasticRecord;
// the triangle records' albedo holds its diffuse base).
constexpr uint32_t kShapePlastic = 64;
// Its textured reflectance is a checkerboard (CheckerboardRecord), which
// the kernel evaluates itself; other textures are called lane by lane.
constexpr uint32_t kShapeCheckerboard = 128;

// A rough conductor's parameters (Mitsuba's roughconductor, Beckmann,
// visible normals), by shape id.
struct alignas(64) ConductorRecord {
  float alpha_u, alpha_v;  // as MicrofacetDistribution keeps them (at least 1e-4)
  float eta[3], k[3];      // the complex index of refraction per channel
  float specular[3];       // specular_reflectance (a constant)
  float unused[5];
};
static_assert(sizeof(ConductorRecord) == 64);

// A smooth plastic's parameters (Mitsuba's plastic, plastic.cpp), by shape
// id, as the scalar code computes them per call.
struct alignas(64) PlasticRecord {
  float eta;              // int_ior / ext_ior
  float rcp_eta;          // 1 / eta
  float inv_eta2;         // 1 / (eta eta)
  float specular_weight;  // Bsdf::specular_sampling_weight
  float specular[3];      // specular_reflectance (a constant)
  float unused[9];
};
static_assert(sizeof(PlasticRecord) == 64);

// A checkerboard reflectance (Texture::eval_varying), by shape id: its uv
// transform and its two colours.
struct alignas(64) CheckerboardRecord {
  float a, b, c, d, e, f;  // UvTransform
  float color0[3], color1[3];
  float unused[4];
};
static_assert(sizeof(CheckerboardRecord) == 64);

// A sphere area emitter, by emitter index (radius 0 for other emitters).
struct alignas(64) SphereEmitterRecord {
  float center[3];
  float radius;
  float radiance[3];
  float flip;  // -1 with flip_normals, else 1
  float unused[8];
};
static_assert(sizeof(SphereEmitterRecord) == 64);

// A slot of an alias table as core/math/alias_table.h lays it out
// (AliasSlot; vector_scene.cpp checks that the two agree).
struct AliasSlotRecord {
  float q;
  uint32_t alias;
  float pmf, alias_pmf;
};

// The environment map, where the scene's environment is one: FrameScene's
// tables (Distribution2D), its texels and its frame, which the kernel
// samples as FrameScene::sample_emitter_direction does.
struct EnvmapRecord {
  const AliasSlotRecord* marginal;  // `height` slots
  const AliasSlotRecord* rows;      // `width` slots per row
  int width, height;
  const float* texels;  // `channels` floats per texel, rows of image_width
  int image_width, image_height, channels;
  double to_world[3][3];  // Transform::vector's rows
  double to_local[3][3];  // the inverse's (EnvmapTables::to_local)
  float scale;
  uint32_t emitter;  // its index among the scene's emitters
};

// FrameScene::sample_emitter_direction's answer, as plain data.
struct EmitterSampleLane {
  float d[3];
  float dist;  // infinity for an emitter at infinity
  float pdf;
  float weight[3];
  int32_t delta;  // -1 for a Dirac emitter (point, spot, directional), else 0
};
// Calls FrameScene::sample_emitter_direction on `scene` (a FrameScene) at
// the point p, with the three numbers sample_emitter draws.
using SampleEmitterFn = void (*)(const void* scene, const float p[3], float u_select, float ux, float uy,
                                 EmitterSampleLane* out);

// The scene as the kernel sees it (pointers into VectorScene's arrays).
struct VectorSceneView {
  const VectorTriangleRecord* triangles = nullptr;
  // Null when every triangle is flat and untextured.
  const ShadingRecord* shading = nullptr;
  const uint32_t* shape_first = nullptr;      // shape id -> its first record
  const uint32_t* shape_flags = nullptr;      // shape id -> the kShape* bits above
  // shape id -> its conductor's parameters where kShapeConductor is set.
  const ConductorRecord* shape_conductor = nullptr;
  // shape id -> its plastic's parameters where kShapePlastic is set.
  const PlasticRecord* shape_plastic = nullptr;
  // shape id -> its reflectance where that is a texture (else null; the
  // record holds the constant).
  const Texture* const* shape_texture = nullptr;
  // shape id -> its checkerboard where kShapeCheckerboard is set.
  const CheckerboardRecord* shape_checkerboard = nullptr;
  // Null unless every emitter is an area emitter on a flat-shaded mesh;
  // next-event estimation then calls sample_emitter lane by lane.
  const EmitterTriangleRecord* emitter_triangles = nullptr;
  SampleEmitterFn sample_emitter = nullptr;
  // emitter -> its sphere, where the scene has sphere emitters (else null):
  // the kernel samples those from outside the sphere itself.
  const SphereEmitterRecord* emitter_spheres = nullptr;
  // The environment map, where the environment is one with a positive
  // weight (else null): the kernel samples it itself.
  const EnvmapRecord* envmap = nullptr;
  const void* frame_scene = nullptr;  // sample_emitter's first argument
  const uint32_t* emitter_first = nullptr;  // emitter -> its first emitter record
  // emitter -> its triangles' area distribution (FrameScene's, so the same
  // index and remapped number for the same u).
  const Distribution1D* const* emitter_choice = nullptr;
  uint32_t emitter_count = 0;
  float select_pdf = 0;  // 1 / emitter_count, as FrameScene computes it
  int rr_depth = 0;
};

// kVectorBatch paths, field by field. The driver fills the ray, the hit and
// `shade`; the kernel shades the lanes marked in `shade` and leaves the
// others as they were. What it makes of a lane it shades depends on that
// lane's rng_state, rng_inc, d, throughput, eta, depth and hit alone (other
// fields it overwrites, or, like result and direct, leaves alone).
// move_shaded_lane (vector_batch.cpp), which packs the shaded lanes
// together before each pass, moves exactly those, so a new input of the
// kernel's goes there too (VectorBatchTest catches a missing one as lanes
// that differ from the scalar stages).
struct alignas(64) VectorBatchState {
  uint64_t rng_state[kVectorBatch], rng_inc[kVectorBatch];  // the path's Pcg32
  alignas(64) float o[3][kVectorBatch], d[3][kVectorBatch];   // the ray traced next
  alignas(64) float tmin[kVectorBatch], tmax[kVectorBatch];
  alignas(64) float throughput[3][kVectorBatch], result[3][kVectorBatch], direct[3][kVectorBatch];
  alignas(64) float prev_p[3][kVectorBatch], prev_pdf[kVectorBatch];
  // The relative index of refraction along the path (PathState::eta), for
  // Russian roulette: a lane that went through glass on the scalar stages
  // carries it into the kernel's vertices, which leave it as it is.
  alignas(64) float eta[kVectorBatch];
  alignas(64) int32_t prev_delta[kVectorBatch], depth[kVectorBatch];
  // The closest hit of the ray (shape id, triangle, barycentrics).
  alignas(64) int32_t hit_shape[kVectorBatch], hit_prim[kVectorBatch];
  alignas(64) float hit_u[kVectorBatch], hit_v[kVectorBatch];
  alignas(64) int32_t shade[kVectorBatch];      // in: -1 shades this lane's vertex, 0 leaves it
  alignas(64) int32_t continues[kVectorBatch];  // out: -1 where the path has a next ray
  // Out: next-event estimation waiting for its shadow ray.
  alignas(64) float shadow_o[3][kVectorBatch], shadow_d[3][kVectorBatch], shadow_tmax[kVectorBatch];
  alignas(64) float shadow_contribution[3][kVectorBatch];
  alignas(64) int32_t shadow_pending[kVectorBatch];  // -1 or 0
};

// One vertex for every lane marked in state->shade (a diffuse, rough
// conductor or smooth plastic triangle): the hit's shading, next-event estimation, the
// BSDF's bounce and Russian roulette, with path_stages.h's arithmetic in
// its order, so every lane comes out bit for bit as sample_emitter,
// connect_emitter and sample_bsdf leave a PathState. One entry point per
// instruction set (vector_vertex_kernel.inl), each callable only where the
// CPU has it.
void shade_vector_vertices_avx2(const VectorSceneView& scene, VectorBatchState* state);
void shade_vector_vertices_avx512(const VectorSceneView& scene, VectorBatchState* state);

// add_emission for lanes[0..n), whose rays left the scene, where the scene
// view has an environment map (VectorSceneView::envmap): its radiance along
// each ray, MIS-weighted against sampling it, added to the lane's sums
// (direct too at depth 0), bit for bit as the scalar stage adds it.
// `hide_camera_rays`: PathTracerSettings::hide_emitters.
void add_environment_avx2(const VectorSceneView& scene, VectorBatchState* state, const int32_t* lanes, int n,
                          bool hide_camera_rays);
void add_environment_avx512(const VectorSceneView& scene, VectorBatchState* state, const int32_t* lanes, int n,
                            bool hide_camera_rays);

}  // namespace gdvr
