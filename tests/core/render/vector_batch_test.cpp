// The vector path batch (core/render/vector_batch.h) against the scalar
// batch: on scenes that FrameScene lays out as records (diffuse, rough
// conductor and smooth plastic meshes; spheres and other BSDFs by the scalar
// stages), every path's radiance must be the same bit for bit, through the
// same rays cast in the same streams, whatever max_depth, Russian roulette
// depth and emitter visibility; and scenes that do not fit must say why.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

#include "core/render/vector_batch.h"
#include "core/render/path_batch.h"
#include "core/render/pt_integrator.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

using test::load_test_scene;

constexpr int kW = 24, kH = 20;

bool same_bits(const Rgb& a, const Rgb& b) { return std::memcmp(&a, &b, sizeof(Rgb)) == 0; }

bool same_ray(const RecordedRay& a, const RecordedRay& b) {
  return std::memcmp(&a.ray, &b.ray, sizeof(Ray)) == 0 && a.shadow == b.shadow && a.set == b.set &&
         a.coherent == b.coherent && a.stream == b.stream;
}

// The scene in `xml` (files relative to `dir`) as *desc and its FrameScene,
// the shapes in `animated` instanced.
std::unique_ptr<FrameScene> load_xml_scene(const std::string& xml, const std::string& dir, Scene* desc,
                                           std::initializer_list<size_t> animated) {
  auto loaded = load_mitsuba_scene_from_string(xml, dir, LoadOptions{});
  EXPECT_TRUE(loaded.ok()) << loaded.status().to_string();
  if (!loaded.ok()) return nullptr;
  *desc = std::move(loaded.value());
  std::vector<bool> animate(desc->shapes.size(), false);
  for (size_t i : animated) animate[i] = true;
  auto fs = FrameScene::create(*desc, animate);
  EXPECT_TRUE(fs.ok()) << fs.status().to_string();
  return fs.ok() ? std::move(fs.value()) : nullptr;
}

// A room (an inward-facing cube, checkered through its uvs) lit by two area
// emitters: a fan of triangles of unequal areas (so that picking a triangle
// searches the distribution; checkered through its barycentrics, as it has
// no uvs) and a flipped rectangle; a black panel and a two-sided red one
// stand in it, and a panel whose reflectance is a bitmap (an EXR; its lanes
// call Texture::eval_varying, the checkerboards' are the kernel's own).
// With `animated`, the fan and the red panel are animated (instanced) shapes.
constexpr size_t kFan = 1, kRedPanel = 4;
std::unique_ptr<FrameScene> load_room(Scene* desc, bool animated = false) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "gdvr_vector_batch_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream obj(dir / "fan.obj");
    obj << "v 0 0.95 0\nv 0.5 0.95 0\nv 0.1 0.95 0.3\nv -0.4 0.95 0.2\nv -0.2 0.95 -0.5\n"
           "f 1 3 2\nf 1 4 3\nf 1 5 4\nf 1 2 5\n";
  }
  std::filesystem::copy_file(std::string(GDVR_SOURCE_DIR) + "/scenes/matpreview/envmap.exr", dir / "bitmap.exr",
                             std::filesystem::copy_options::overwrite_existing);
  const std::string xml = R"(<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="8"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="70"/>
    <transform name="to_world"><lookat origin="0, 0, -0.9" target="0, 0, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="20"/></film>
  </sensor>
  <texture type="checkerboard" id="checks">
    <rgb name="color0" value="0.8, 0.7, 0.6"/><rgb name="color1" value="0.3, 0.5, 0.2"/>
    <transform name="to_uv"><scale x="5" y="3"/></transform>
  </texture>
  <bsdf type="diffuse" id="wall"><ref name="reflectance" id="checks"/></bsdf>
  <shape type="cube"><boolean name="flip_normals" value="true"/><ref id="wall"/></shape>
  <shape type="obj">
    <string name="filename" value="fan.obj"/>
    <bsdf type="diffuse"><ref name="reflectance" id="checks"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter>
  </shape>
  <shape type="rectangle">
    <boolean name="flip_normals" value="true"/>
    <transform name="to_world"><scale value="0.2"/><rotate y="1" angle="90"/><translate x="0.9" y="-0.3" z="0.4"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.9, 0.3"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="1, 3, 9"/></emitter>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><translate x="-0.3" y="-0.2" z="0.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.25"/><rotate x="1" angle="70"/><translate x="0.3" y="-0.6" z="0.2"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.9, 0, 0"/></bsdf></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><rotate y="1" angle="-50"/><translate x="-0.5" y="-0.5" z="0.6"/></transform>
    <bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="bitmap.exr"/></texture></bsdf>
  </shape>
</scene>)";
  if (!animated) return load_xml_scene(xml, dir.string(), desc, {});
  return load_xml_scene(xml, dir.string(), desc, {kFan, kRedPanel});
}

// A plastic cube whose diffuse reflectance is a texture and a sphere light:
// nothing the kernel shades.
std::unique_ptr<FrameScene> load_scene_without_records(Scene* desc) {
  return load_xml_scene(R"(<scene version="3.0.0">
    <sensor type="perspective">
      <transform name="to_world"><lookat origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
      <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <shape type="cube"><bsdf type="plastic"><texture type="checkerboard" name="diffuse_reflectance"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="1" y="1.5" z="-1.5"/><float name="radius" value="0.3"/>
      <emitter type="area"><rgb name="radiance" value="10, 10, 10"/></emitter></shape>
    <emitter type="constant"><rgb name="radiance" value="0.5, 0.5, 0.5"/></emitter>
  </scene>)", std::filesystem::temp_directory_path().string(), desc, {});
}

TEST(VectorSceneTest, QualifyingScenesHaveRecordsAndOthersSayWhyNot) {
  auto cbox = load_test_scene("cbox", kW, kH);
  ASSERT_TRUE(cbox);
  EXPECT_NE(cbox->scene->vector_scene(), nullptr) << cbox->scene->why_not_vector();
  EXPECT_GT(cbox->scene->vector_scene()->memory_bytes(), 0u);
  Scene room_desc;
  auto room = load_room(&room_desc);
  ASSERT_TRUE(room);
  EXPECT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  // The walls' checkerboard is the kernel's; the bitmap panel's texture is called.
  const VectorSceneView& rv = room->vector_scene()->view();
  EXPECT_EQ(rv.shape_flags[0] & (kShapeTextured | kShapeCheckerboard), kShapeTextured | kShapeCheckerboard);
  EXPECT_EQ(rv.shape_checkerboard[0].a, 5.0f);
  EXPECT_EQ(rv.shape_flags[5] & (kShapeTextured | kShapeCheckerboard), kShapeTextured);

  // Rough conductors are shaded by the kernel, the sphere lights by the
  // scalar stages (kShapeScalar), and next-event estimation asks FrameScene.
  auto veach = load_test_scene("veach-mis", kW, kH);
  ASSERT_TRUE(veach);
  ASSERT_NE(veach->scene->vector_scene(), nullptr) << veach->scene->why_not_vector();
  const VectorSceneView& vv = veach->scene->vector_scene()->view();
  EXPECT_EQ(vv.emitter_triangles, nullptr);
  int conductors = 0, scalar = 0;
  for (size_t i = 0; i < veach->desc.shapes.size(); ++i) {
    conductors += (vv.shape_flags[i] & kShapeConductor) != 0;
    scalar += (vv.shape_flags[i] & kShapeScalar) != 0;
  }
  EXPECT_EQ(conductors, 4);
  EXPECT_EQ(scalar, 3);  // the three sphere lights
  // The environment is looked up along rays that leave and sampled, and the
  // plastic shape shaded, all by the kernel.
  auto matpreview = load_test_scene("matpreview", kW, kH);
  ASSERT_TRUE(matpreview);
  ASSERT_NE(matpreview->scene->vector_scene(), nullptr) << matpreview->scene->why_not_vector();
  const VectorSceneView& mv = matpreview->scene->vector_scene()->view();
  EXPECT_NE(mv.shape_flags[0] & kShapeTextured, 0u);  // the checkerboard floor
  EXPECT_EQ(mv.shape_flags[1] & ~kShapeHasUvs, 0u);   // the diffuse interior
  EXPECT_EQ(mv.shape_flags[2] & ~kShapeHasUvs, kShapePlastic);  // the plastic exterior
  EXPECT_NE(mv.envmap, nullptr);
  EXPECT_FLOAT_EQ(mv.shape_plastic[2].eta, 1.9f / 1.000277f);
  EXPECT_EQ(mv.shape_plastic[2].specular[0], 1.0f);
  // Its records hold the diffuse base R / (1 - Fdr_int), not R.
  const VectorTriangleRecord& plastic_tri = mv.triangles[mv.shape_first[2]];
  EXPECT_GT(plastic_tri.albedo[0], 0.940f);
  EXPECT_FLOAT_EQ(plastic_tri.albedo[0] / plastic_tri.albedo[1], 0.940f / 0.271f);
  // Nothing for the kernel to shade: the scalar batch renders it.
  Scene none_desc;
  auto none = load_scene_without_records(&none_desc);
  ASSERT_TRUE(none);
  EXPECT_EQ(none->vector_scene(), nullptr);
  EXPECT_NE(none->why_not_vector().find("no shape is a triangle mesh"), std::string::npos) << none->why_not_vector();

  // What the frame statistics say was left out.
  PathTracerSettings settings;
  EXPECT_EQ(why_no_vector_batch(*none, settings, kPathBatch), none->why_not_vector());
  EXPECT_NE(why_no_vector_batch(*cbox->scene, settings, 1).find("1 at a time"), std::string::npos);
  EXPECT_EQ(why_no_vector_batch(*cbox->scene, settings, kPathBatch).empty(), vector_batch_available(*cbox->scene));
  settings.vector_kernels = false;
  EXPECT_NE(why_no_vector_batch(*cbox->scene, settings, kPathBatch).find("switched off"), std::string::npos);
}

// The kernels offered are those the CPU can run, fastest first.
TEST(VectorBatchTest, KernelsAreThoseThisCpuRuns) {
  const std::vector<VectorKernel>& kernels = vector_kernels();
#if defined(__x86_64__)
  const bool avx2 = __builtin_cpu_supports("avx2");
  const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                      __builtin_cpu_supports("avx512dq");
  ASSERT_EQ(kernels.size(), size_t(avx2) + size_t(avx512));
  if (avx512) {
    EXPECT_STREQ(kernels.front().isa, "avx512");
  }
  if (avx2) {
    EXPECT_STREQ(kernels.back().isa, "avx2");
  }
#else
  EXPECT_TRUE(kernels.empty());
#endif
}

struct Variant {
  int max_depth, rr_depth;
  bool hide_emitters;
  // Of the paths, at least this fraction carry light (the comparison is not
  // one of black paths). max_depth 1 sees emitters only directly: it checks
  // the hand-over to the scalar stages before any vertex, and its rays.
  float lit_fraction;
};

// Four consecutive samples per pixel, as trace_tile_samples starts them, of
// pixels spread over the image.
void start_paths(const FrameScene& scene, int w, int h, int n, std::vector<PathState>* paths) {
  PerspectiveCamera camera(scene.scene().camera, w, h);
  paths->resize(size_t(n));
  for (int i = 0; i < n; ++i) {
    const int pixel = (i / 4 * 37) % (w * h), x = pixel % w, y = pixel / w;
    Sampler sampler(42, 3, uint32_t(x), uint32_t(y), uint32_t(i % 4));
    const Vec2f j = sampler.next_2d();
    start_path(&(*paths)[size_t(i)], camera.generate_ray({float(x) + j.x, float(y) + j.y}), sampler);
  }
}

// Batches of kPathBatch paths and a partial one, vector (every kernel this CPU
// runs) against scalar.
void expect_kernel_same_as_scalar_batch(const FrameScene& scene, const Variant& v, int w, int h,
                                        const VectorKernel& kernel);
void expect_same_as_scalar_batch(const FrameScene& scene, const Variant& v, int w, int h) {
  for (const VectorKernel& kernel : vector_kernels()) expect_kernel_same_as_scalar_batch(scene, v, w, h, kernel);
}
void expect_kernel_same_as_scalar_batch(const FrameScene& scene, const Variant& v, int w, int h,
                                        const VectorKernel& kernel) {
  PathTracerSettings settings;
  settings.max_depth = v.max_depth;
  settings.rr_depth = v.rr_depth;
  settings.hide_emitters = v.hide_emitters;
  const std::string what = std::string(kernel.isa) + ", max_depth " + std::to_string(v.max_depth) + ", rr_depth " + std::to_string(v.rr_depth) +
                           (v.hide_emitters ? ", emitters hidden" : "");
  constexpr int kPaths = 3 * kPathBatch + 23;
  std::vector<PathState> scalar_paths, vector_paths;
  start_paths(scene, w, h, kPaths, &scalar_paths);
  start_paths(scene, w, h, kPaths, &vector_paths);
  std::vector<PathSample> scalar(kPaths), vector(kPaths);
  std::vector<RecordedRay> scalar_log, vector_log;
  PathCounters scalar_counters, vector_counters;
  scalar_counters.ray_log = &scalar_log;
  vector_counters.ray_log = &vector_log;
  trace_path_batch(scene, settings, scalar_paths.data(), kPaths, scalar_counters, scalar.data());
  RayStream stream;
  for (int base = 0; base < kPaths; base += kPathBatch)
    trace_vector_batch(scene, settings, vector_paths.data() + base, std::min(kPathBatch, kPaths - base), stream,
                       vector_counters, vector.data() + base, &kernel);
  int nonzero = 0, differ = 0;
  for (int i = 0; i < kPaths; ++i) {
    const bool same = same_bits(scalar[size_t(i)].radiance, vector[size_t(i)].radiance) &&
                      same_bits(scalar[size_t(i)].direct, vector[size_t(i)].direct);
    if (!same && differ++ < 5)
      ADD_FAILURE() << what << ": path " << i << " scalar (" << scalar[size_t(i)].radiance.r << ", "
                    << scalar[size_t(i)].radiance.g << ", " << scalar[size_t(i)].radiance.b << ") vector ("
                    << vector[size_t(i)].radiance.r << ", " << vector[size_t(i)].radiance.g << ", "
                    << vector[size_t(i)].radiance.b << ")";
    nonzero += !scalar[size_t(i)].radiance.is_black();
  }
  EXPECT_EQ(differ, 0) << what;
  EXPECT_GE(nonzero, int(v.lit_fraction * kPaths)) << what;
  EXPECT_EQ(scalar_counters.rays, vector_counters.rays) << what;
  EXPECT_EQ(scalar_counters.streams_logged, vector_counters.streams_logged) << what;
  ASSERT_EQ(scalar_log.size(), vector_log.size()) << what;
  for (size_t k = 0; k < scalar_log.size(); ++k)
    ASSERT_TRUE(same_ray(scalar_log[k], vector_log[k])) << what << ": ray " << k;
}

const Variant kVariants[] = {
    {-1, 5, true, 0.5f}, {6, 5, true, 0.5f},  {6, 5, false, 0.5f}, {1, 5, false, 0.0f},
    {2, 5, true, 0.2f},  {3, 1, false, 0.4f}, {12, 2, true, 0.5f},
};

// A bundled scene (load_test_scene), in every setting.
void expect_bundled_scene_same_as_scalar_batch(const std::string& name) {
  auto ts = load_test_scene(name, kW, kH);
  ASSERT_TRUE(ts);
  if (!vector_batch_available(*ts->scene)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  for (const Variant& v : kVariants) expect_same_as_scalar_batch(*ts->scene, v, kW, kH);
}

TEST(VectorBatchTest, CboxPathsMatchTheScalarBatchBitForBit) { expect_bundled_scene_same_as_scalar_batch("cbox"); }

TEST(VectorBatchTest, VeachMisPathsMatchTheScalarBatchBitForBit) {
  expect_bundled_scene_same_as_scalar_batch("veach-mis");
}

// The room with glossy panels: rough Beckmann conductors (two-sided and
// one-sided, isotropic and anisotropic, from nearly smooth to rough, one
// with a roughness under the 1e-4 floor), lit by a sphere light (close
// enough to the ceiling that its cone is sampled in double there), a
// flipped one (dark from outside), a point light, a spot light and a
// directional light (blocked by the walls: its
// shadow rays are unbounded); a plastic cube (the kernel's) and a diffuse
// sphere (the scalar stages').
// The camera of the rooms below, looking into a unit cube from near its
// front wall.
constexpr const char* kRoomCamera = R"(
  <sensor type="perspective">
    <float name="fov" value="80"/>
    <transform name="to_world"><lookat origin="0, 0, -0.9" target="0, -0.2, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="20"/></film>
  </sensor>)";

// Shapes of the glossy room.
constexpr size_t kGlossyPanel = 1, kSphereLight = 7;
std::unique_ptr<FrameScene> load_glossy_room(Scene* desc, bool animated = false) {
  const std::string conductor = R"(<string name="distribution" value="beckmann"/>
      <rgb name="specular_reflectance" value="0.9, 0.8, 0.6"/>
      <rgb name="eta" value="0.200438, 0.924033, 1.10221"/><rgb name="k" value="3.91295, 2.45285, 2.14219"/>)";
  const std::string xml = R"(<scene version="3.0.0">)" + std::string(kRoomCamera) + R"(
  <shape type="cube"><boolean name="flip_normals" value="true"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.5"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.35"/><rotate x="1" angle="80"/><translate x="-0.4" y="-0.7" z="0.4"/></transform>
    <bsdf type="twosided"><bsdf type="roughconductor"><float name="alpha" value="0.05"/>)" + conductor + R"(</bsdf></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><rotate y="1" angle="60"/><translate x="0.5" y="-0.2" z="0.5"/></transform>
    <bsdf type="roughconductor"><float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.08"/>)" + conductor + R"(</bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.25"/><rotate x="1" angle="-30"/><translate x="0.1" y="0.3" z="0.8"/></transform>
    <bsdf type="twosided"><bsdf type="roughconductor"><float name="alpha" value="0.00001"/>)" + conductor + R"(</bsdf></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><translate x="-0.5" y="0.2" z="0.7"/></transform>
    <bsdf type="twosided"><bsdf type="roughconductor"><float name="alpha" value="0.6"/>)" + conductor + R"(</bsdf></bsdf>
  </shape>
  <shape type="cube">
    <transform name="to_world"><scale value="0.15"/><rotate y="1" angle="30"/><translate x="0.2" y="-0.8" z="0.2"/></transform>
    <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.8"/></bsdf>
  </shape>
  <shape type="sphere">
    <point name="center" x="-0.1" y="-0.75" z="0.6"/><float name="radius" value="0.2"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.3"/></bsdf>
  </shape>
  <shape type="sphere">
    <point name="center" x="0.3" y="0.7" z="0.3"/><float name="radius" value="0.1"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="40, 30, 20"/></emitter>
  </shape>
  <shape type="sphere">
    <point name="center" x="-0.6" y="0.75" z="0.6"/><float name="radius" value="0.15"/>
    <boolean name="flip_normals" value="true"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="20, 20, 30"/></emitter>
  </shape>
  <emitter type="point"><point name="position" x="-0.5" y="0.6" z="0.0"/><rgb name="intensity" value="1, 2, 3"/></emitter>
  <emitter type="spot">
    <transform name="to_world"><lookat origin="0.6, 0.6, -0.5" target="0, -1, 0.5" up="0, 1, 0"/></transform>
    <rgb name="intensity" value="5, 5, 5"/><float name="cutoff_angle" value="30"/><float name="beam_width" value="20"/>
  </emitter>
  <emitter type="directional"><vector name="direction" x="0.3" y="-1" z="0.2"/><rgb name="irradiance" value="2, 2, 2"/></emitter>
</scene>)";
  const std::string dir = std::filesystem::temp_directory_path().string();
  if (!animated) return load_xml_scene(xml, dir, desc, {});
  return load_xml_scene(xml, dir, desc, {kGlossyPanel, kSphereLight});
}

// An animated conductor panel and sphere light: the records follow them
// through FrameScene::update (the sphere's centre moves in its record).
TEST(VectorBatchTest, AnimatedGlossyRoomMatchesTheScalarBatchAfterUpdates) {
  Scene desc;
  auto room = load_glossy_room(&desc, /*animated=*/true);
  ASSERT_TRUE(room);
  ASSERT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  if (!vector_batch_available(*room)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  expect_same_as_scalar_batch(*room, kVariants[2], kW, kH);
  const float x0 = room->vector_scene()->view().emitter_spheres[0].center[0];
  Scene moved = desc;
  moved.shapes[kSphereLight].to_world = Transform::translate({-0.3f, -0.1f, 0.1f}) * desc.shapes[kSphereLight].to_world;
  moved.shapes[kGlossyPanel].to_world =
      Transform::translate({0.1f, 0.1f, -0.1f}) * Transform::rotate({0, 1, 0}, 25.0f) * desc.shapes[kGlossyPanel].to_world;
  ASSERT_TRUE(room->update(moved).ok());
  ASSERT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  EXPECT_FLOAT_EQ(room->vector_scene()->view().emitter_spheres[0].center[0], x0 - 0.3f);
  expect_same_as_scalar_batch(*room, kVariants[2], kW, kH);
  expect_same_as_scalar_batch(*room, kVariants[0], kW, kH);
}

TEST(VectorBatchTest, GlossyRoomPathsMatchTheScalarBatchBitForBit) {
  Scene desc;
  auto room = load_glossy_room(&desc);
  ASSERT_TRUE(room);
  ASSERT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  const VectorSceneView& view = room->vector_scene()->view();
  EXPECT_EQ(view.emitter_triangles, nullptr);
  for (size_t i : {1, 3, 4}) EXPECT_NE(view.shape_flags[i] & kShapeConductor, 0u) << "shape " << i;
  // Anisotropic: its frame follows dp/du (FrameScene::interaction), which the kernel does not build.
  EXPECT_NE(view.shape_flags[2] & kShapeScalar, 0u);
  EXPECT_NE(view.shape_flags[5] & kShapePlastic, 0u);
  for (size_t i : {6, 7, 8}) EXPECT_NE(view.shape_flags[i] & kShapeScalar, 0u) << "shape " << i;
  ASSERT_NE(view.emitter_spheres, nullptr);
  EXPECT_EQ(view.emitter_spheres[1].flip, -1.0f);
  EXPECT_EQ(view.shape_conductor[4].alpha_u, 0.6f);
  EXPECT_EQ(view.shape_conductor[3].alpha_u, 1e-4f);  // MicrofacetDistribution's floor
  if (!vector_batch_available(*room)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  for (const Variant& v : kVariants) expect_same_as_scalar_batch(*room, v, kW, kH);
}

// Meshes and a sphere that reflect nothing (kShapeReflectsNothing): a black
// rectangle light, a black cube and a black sphere end the paths that reach
// them, after the light's emission.
TEST(VectorBatchTest, ShapesThatReflectNothingEndPathsAsTheScalarBatchDoes) {
  Scene desc;
  auto room = load_xml_scene(R"(<scene version="3.0.0">)" + std::string(kRoomCamera) + R"(
  <shape type="cube"><boolean name="flip_normals" value="true"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.6, 0.4"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.4"/><rotate y="1" angle="20"/><translate x="-0.4" y="-0.2" z="0.6"/></transform>
    <bsdf type="twosided"><bsdf type="roughconductor"><string name="distribution" value="beckmann"/>
      <float name="alpha" value="0.15"/><string name="material" value="Cu"/></bsdf></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate x="0.1" y="0.98" z="0.3"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="8, 8, 6"/></emitter>
  </shape>
  <shape type="cube"><transform name="to_world"><scale value="0.2"/><translate x="0.5" y="-0.8" z="0.4"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf></bsdf></shape>
  <shape type="sphere"><point name="center" x="-0.1" y="-0.75" z="0.2"/><float name="radius" value="0.2"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf></shape>
</scene>)", std::filesystem::temp_directory_path().string(), &desc, {});
  ASSERT_TRUE(room);
  ASSERT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  const VectorSceneView& view = room->vector_scene()->view();
  EXPECT_EQ(view.shape_flags[0] & kShapeReflectsNothing, 0u);
  EXPECT_EQ(view.shape_flags[1] & kShapeReflectsNothing, 0u);
  for (size_t i : {2, 3, 4}) EXPECT_NE(view.shape_flags[i] & kShapeReflectsNothing, 0u) << "shape " << i;
  EXPECT_NE(view.shape_flags[4] & kShapeScalar, 0u);
  if (!vector_batch_available(*room)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  for (const Variant& v : kVariants) expect_same_as_scalar_batch(*room, v, kW, kH);
}

// matpreview: an environment map seen along rays that leave (and at last
// rays) and sampled, both by the kernel; a checkerboard floor; the plastic
// shape, shaded by the kernel.
TEST(VectorBatchTest, MatpreviewPathsMatchTheScalarBatchBitForBit) {
  expect_bundled_scene_same_as_scalar_batch("matpreview");
}

// An open yard under a constant sky: a diffuse floor, a rough conductor
// panel, a plastic cube, a black rectangle light and a black sphere that
// reflect nothing (the path ends there).
TEST(VectorBatchTest, OpenYardUnderConstantSkyMatchesTheScalarBatchBitForBit) {
  Scene desc;
  auto yard = load_xml_scene(R"(<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="70"/>
    <transform name="to_world"><lookat origin="0, 1.2, -3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="20"/></film>
  </sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.6, 0.4"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.6"/><rotate y="1" angle="20"/><translate x="-0.6" y="0.6" z="0.5"/></transform>
    <bsdf type="twosided"><bsdf type="roughconductor"><string name="distribution" value="beckmann"/>
      <float name="alpha" value="0.15"/><string name="material" value="Cu"/></bsdf></bsdf>
  </shape>
  <shape type="cube"><transform name="to_world"><scale value="0.3"/><translate x="0.6" y="0.3" z="0"/></transform>
    <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.8, 0.2, 0.2"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="120"/><translate x="0.2" y="1.4" z="0.3"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="8, 8, 6"/></emitter>
  </shape>
  <shape type="sphere"><point name="center" x="-0.1" y="0.25" z="-0.6"/><float name="radius" value="0.25"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf></shape>
  <emitter type="constant"><rgb name="radiance" value="0.8, 0.9, 1.2"/></emitter>
</scene>)", std::filesystem::temp_directory_path().string(), &desc, {});
  ASSERT_TRUE(yard);
  ASSERT_NE(yard->vector_scene(), nullptr) << yard->why_not_vector();
  const VectorSceneView& view = yard->vector_scene()->view();
  EXPECT_EQ(view.shape_flags[3] & ~kShapeHasUvs, kShapeReflectsNothing);  // the rectangle light
  EXPECT_EQ(view.shape_flags[4], kShapeScalar | kShapeReflectsNothing);  // the black sphere
  if (!vector_batch_available(*yard)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  for (const Variant& v : kVariants) expect_same_as_scalar_batch(*yard, v, kW, kH);
}

// Smooth plastics in a room lit by a rectangle light and a constant sky
// through an open side: one-sided and two-sided, nonlinear, a coloured
// specular reflectance, an index-matched coating (eta 1: no Fresnel
// reflection, never the Dirac lobe), a coating denser outside than in
// (eta < 1), and a textured one that the scalar stages shade.
TEST(VectorBatchTest, PlasticRoomMatchesTheScalarBatchBitForBit) {
  Scene desc;
  auto room = load_xml_scene(R"(<scene version="3.0.0">)" + std::string(kRoomCamera) + R"(
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><translate y="-1"/></transform>
    <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.5, 0.6, 0.4"/><float name="int_ior" value="1.7"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><translate z="1"/></transform>
    <bsdf type="twosided"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.2, 0.3, 0.8"/>
      <boolean name="nonlinear" value="true"/></bsdf></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="90"/><translate x="-1"/></transform>
    <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.7, 0.7, 0.7"/>
      <rgb name="specular_reflectance" value="0.9, 0.5, 0.2"/></bsdf></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.2"/><rotate y="1" angle="30"/><translate x="0.3" y="-0.8" z="0.4"/></transform>
    <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.8, 0.2, 0.2"/>
      <float name="int_ior" value="1.333"/><float name="ext_ior" value="1.333"/></bsdf></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.15"/><translate x="-0.4" y="-0.85" z="0.3"/></transform>
    <bsdf type="twosided"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.3, 0.8, 0.3"/>
      <float name="int_ior" value="1.2"/><float name="ext_ior" value="1.6"/></bsdf></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.25"/><rotate x="1" angle="60"/><translate x="-0.1" y="-0.4" z="0.7"/></transform>
    <bsdf type="plastic"><texture type="checkerboard" name="diffuse_reflectance"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate x="0.1" y="0.98" z="0.3"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="8, 8, 6"/></emitter>
  </shape>
  <emitter type="constant"><rgb name="radiance" value="0.4, 0.5, 0.7"/></emitter>
</scene>)", std::filesystem::temp_directory_path().string(), &desc, {});
  ASSERT_TRUE(room);
  ASSERT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  const VectorSceneView& view = room->vector_scene()->view();
  for (size_t i : {0, 1, 2, 3, 4}) EXPECT_NE(view.shape_flags[i] & kShapePlastic, 0u) << "shape " << i;
  EXPECT_NE(view.shape_flags[1] & kShapeTwoSided, 0u);
  EXPECT_EQ(view.shape_flags[5], kShapeScalar);  // the textured plastic
  EXPECT_EQ(view.shape_plastic[3].eta, 1.0f);
  EXPECT_LT(view.shape_plastic[4].eta, 1.0f);
  EXPECT_EQ(view.shape_plastic[2].specular[2], 0.2f);
  if (!vector_batch_available(*room)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  for (const Variant& v : kVariants) expect_same_as_scalar_batch(*room, v, kW, kH);
}

TEST(VectorBatchTest, RoomPathsMatchTheScalarBatchBitForBit) {
  Scene desc;
  auto room = load_room(&desc);
  ASSERT_TRUE(room);
  if (!vector_batch_available(*room)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  for (const Variant& v : kVariants) expect_same_as_scalar_batch(*room, v, kW, kH);
}

// A caller that skips vector_batch_available() still gets the scalar
// batch's paths, not a crash, on a scene without records.
// A scene that hides its emitters: camera rays pass through the Cornell box's
// light (FrameScene::camera_geometry) in both batches alike, ray for ray.
TEST(VectorBatchTest, CameraRaysThroughHiddenEmittersMatchTheScalarBatch) {
  auto ts = load_test_scene("cbox", kW, kH);
  ASSERT_TRUE(ts);
  if (!vector_batch_available(*ts->scene)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  Scene desc = ts->desc;
  desc.defaults.hide_emitters = true;
  auto hidden = FrameScene::create(desc, {});
  ASSERT_TRUE(hidden.ok()) << hidden.status().to_string();
  ASSERT_EQ((*hidden)->camera_geometry(), GeometrySet::kNonEmitters);
  for (const Variant& v : kVariants)
    if (v.hide_emitters) expect_same_as_scalar_batch(**hidden, v, kW, kH);
}

TEST(VectorBatchTest, SceneWithoutRecordsFallsBackToTheScalarBatch) {
  Scene desc;
  auto scene = load_scene_without_records(&desc);
  ASSERT_TRUE(scene);
  ASSERT_EQ(scene->vector_scene(), nullptr);
  std::vector<PathState> scalar_paths, vector_paths;
  start_paths(*scene, 8, 8, kPathBatch, &scalar_paths);
  start_paths(*scene, 8, 8, kPathBatch, &vector_paths);
  std::vector<PathSample> scalar(kPathBatch), vector(kPathBatch);
  PathCounters scalar_counters, vector_counters;
  PathTracerSettings settings;
  trace_path_batch(*scene, settings, scalar_paths.data(), kPathBatch, scalar_counters, scalar.data());
  RayStream stream;
  trace_vector_batch(*scene, settings, vector_paths.data(), kPathBatch, stream, vector_counters, vector.data());
  int lit = 0;
  for (int i = 0; i < kPathBatch; ++i) {
    EXPECT_TRUE(same_bits(scalar[size_t(i)].radiance, vector[size_t(i)].radiance)) << "path " << i;
    lit += !scalar[size_t(i)].radiance.is_black();
  }
  EXPECT_GT(lit, 0);
  EXPECT_EQ(scalar_counters.rays, vector_counters.rays);
}

// Animated shapes are baked into the records at each frame's place: before
// and after FrameScene::update moves them, the kernel's paths are the scalar
// batch's.
TEST(VectorBatchTest, AnimatedShapesMatchTheScalarBatchAfterUpdates) {
  Scene desc;
  auto room = load_room(&desc, /*animated=*/true);
  ASSERT_TRUE(room);
  ASSERT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  if (!vector_batch_available(*room)) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  expect_same_as_scalar_batch(*room, kVariants[1], kW, kH);
  Scene moved = desc;
  moved.shapes[kRedPanel].to_world =
      Transform::translate({-0.2f, 0.3f, 0.1f}) * Transform::rotate({0, 1, 0}, 40.0f) * desc.shapes[kRedPanel].to_world;
  moved.shapes[kFan].to_world = Transform::translate({0.1f, -0.05f, 0.2f}) * desc.shapes[kFan].to_world;
  ASSERT_TRUE(room->update(moved).ok());
  ASSERT_NE(room->vector_scene(), nullptr) << room->why_not_vector();
  expect_same_as_scalar_batch(*room, kVariants[1], kW, kH);
  expect_same_as_scalar_batch(*room, kVariants[2], kW, kH);
  // A mirroring transform: interaction() now interpolates the panel's vertex
  // normals (FrameScene::shades_with_face_normal), which the kernel does not
  // do for animated shapes, so the records go and the scalar batch renders.
  moved.shapes[kRedPanel].to_world = Transform::scale({-1.0f, 1.0f, 1.0f}) * moved.shapes[kRedPanel].to_world;
  ASSERT_TRUE(room->update(moved).ok());
  EXPECT_EQ(room->vector_scene(), nullptr);
  EXPECT_NE(room->why_not_vector().find("animated shape 4"), std::string::npos) << room->why_not_vector();
  EXPECT_FALSE(vector_batch_available(*room));
}

// The whole renderer: an image with the vector kernel is the scalar one's,
// on every bundled scene the kernel serves (degenerate.xml holds zero-area
// and needle triangles; furnace.xml is the white furnace; inside_object.xml
// starts paths inside a closed mesh; matpreview has an environment map; in
// glass.xml and tir.xml paths cross dielectrics on the scalar stages and
// carry eta into the kernel's Russian roulette).
class VectorRenderTest : public ::testing::TestWithParam<std::string> {};

TEST_P(VectorRenderTest, RenderIsTheSameWithAndWithoutTheVectorKernel) {
  auto desc = load_mitsuba_scene(std::string(GDVR_SOURCE_DIR) + "/scenes/" + GetParam(), LoadOptions{});
  ASSERT_TRUE(desc.ok()) << desc.status().to_string();
  auto scene = FrameScene::create(desc.value(), {});
  ASSERT_TRUE(scene.ok()) << scene.status().to_string();
  ASSERT_NE(scene.value()->vector_scene(), nullptr) << scene.value()->why_not_vector();
  if (!vector_batch_available(*scene.value())) GTEST_SKIP() << "this CPU has no AVX2: the scalar batch runs";
  FrameRenderSettings rs;
  rs.width = 40;
  rs.height = 30;
  rs.spp = 8;
  rs.seed = 5;
  rs.threads = 2;
  rs.tile_size = 8;
  rs.path.max_depth = desc->defaults.max_depth;
  rs.path.rr_depth = desc->defaults.rr_depth;
  std::vector<FrameRenderResult> results;
  for (bool vector : {false, true}) {
    rs.path.vector_kernels = vector;
    auto r = render_frame_pt(*scene.value(), rs, 0, {});
    ASSERT_TRUE(r.ok()) << r.status().to_string();
    results.push_back(std::move(r.value()));
  }
  EXPECT_GT(results[0].rays, uint64_t(rs.width * rs.height * rs.spp));
  EXPECT_EQ(results[0].rays, results[1].rays);
  ASSERT_EQ(results[0].color.data().size(), results[1].color.data().size());
  EXPECT_EQ(0, std::memcmp(results[0].color.data().data(), results[1].color.data().data(),
                           results[0].color.data().size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(results[0].variance.data().data(), results[1].variance.data().data(),
                           results[0].variance.data().size() * sizeof(float)));
}

INSTANTIATE_TEST_SUITE_P(Scenes, VectorRenderTest,
                         ::testing::Values("cbox/cbox-rgb.xml", "cornell-box/scene.xml", "veach-mis/scene.xml",
                                           "stiff/degenerate.xml", "stiff/furnace.xml", "stiff/inside_object.xml",
                                           "stiff/rough_conductor.xml", "stiff/tiny_light.xml", "stiff/scaled.xml",
                                           "matpreview/matpreview.xml", "stiff/grazing.xml", "stiff/glass.xml",
                                           "stiff/mirror.xml", "stiff/tir.xml"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param.substr(0, info.param.find('.'));
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace gdvr
