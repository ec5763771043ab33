// glTF loader: the bundled samples, small synthetic files for each feature and
// each rejection, and a render through the job runner.
#include "core/scene/gltf_loader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/job/job_runner.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string sample_path(const std::string& rel) { return std::string(GDVR_SOURCE_DIR) + "/scenes/gltf/" + rel; }

fs::path temp_dir(const std::string& name) {
  fs::path dir = fs::path(testing::TempDir()) / ("gdvr_gltf_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string base64(const std::vector<uint8_t>& data) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < data.size(); i += 3) {
    uint32_t v = uint32_t(data[i]) << 16;
    if (i + 1 < data.size()) v |= uint32_t(data[i + 1]) << 8;
    if (i + 2 < data.size()) v |= data[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < data.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < data.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

// A minimal glTF built in code: one triangle on node "tri"; tests add to it.
struct SyntheticGltf {
  Json doc;
  std::vector<uint8_t> bin;

  SyntheticGltf() {
    doc = Json::parse(R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "tri", "mesh": 0}],
        "meshes": [{"name": "triangle", "primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [], "bufferViews": [], "accessors": []})");
    add_accessor({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
  }
  int add_accessor(const std::vector<float>& values, const std::string& type) {
    size_t nc = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : 4;
    size_t offset = bin.size();
    bin.resize(offset + values.size() * 4);
    std::memcpy(bin.data() + offset, values.data(), values.size() * 4);
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * 4}});
    Json acc = {{"bufferView", doc["bufferViews"].size() - 1}, {"componentType", 5126},
                {"count", values.size() / nc}, {"type", type}};
    if (type == "SCALAR") {  // animation inputs need min/max
      acc["min"] = {*std::min_element(values.begin(), values.end())};
      acc["max"] = {*std::max_element(values.begin(), values.end())};
    }
    doc["accessors"].push_back(acc);
    return int(doc["accessors"].size()) - 1;
  }
  void animate(int node, const std::string& path, const std::string& interp, const std::vector<float>& times,
               const std::vector<float>& values) {
    int in = add_accessor(times, "SCALAR");
    int out = add_accessor(values, path == "rotation" ? "VEC4" : "VEC3");
    if (!doc.contains("animations")) doc["animations"] = Json::array({Json{{"channels", Json::array()}, {"samplers", Json::array()}}});
    Json& a = doc["animations"][0];
    a["samplers"].push_back({{"input", in}, {"output", out}, {"interpolation", interp}});
    a["channels"].push_back({{"sampler", a["samplers"].size() - 1}, {"target", {{"node", node}, {"path", path}}}});
  }
  int add_node(Json node) {
    doc["nodes"].push_back(node);
    int index = int(doc["nodes"].size()) - 1;
    doc["scenes"][0]["nodes"].push_back(index);
    return index;
  }
  std::string write(const fs::path& dir, const std::string& name = "scene.gltf") {
    Json d = doc;
    d["buffers"] = {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}};
    fs::path p = dir / name;
    std::ofstream(p) << d.dump(1);
    return p.string();
  }
  std::string write_glb(const fs::path& dir) {
    Json d = doc;
    d["buffers"] = {{{"byteLength", bin.size()}}};
    std::string json = d.dump();
    while (json.size() % 4) json += ' ';
    std::vector<uint8_t> chunk = bin;
    while (chunk.size() % 4) chunk.push_back(0);
    auto u32 = [](std::string* s, uint32_t v) { s->append(reinterpret_cast<const char*>(&v), 4); };
    std::string file = "glTF";
    u32(&file, 2);
    u32(&file, uint32_t(12 + 8 + json.size() + 8 + chunk.size()));
    u32(&file, uint32_t(json.size()));
    file += "JSON";
    file += json;
    u32(&file, uint32_t(chunk.size()));
    file += std::string("BIN\0", 4);
    file.append(reinterpret_cast<const char*>(chunk.data()), chunk.size());
    fs::path p = dir / "scene.glb";
    std::ofstream(p, std::ios::binary) << file;
    return p.string();
  }
};

bool has_warning(const Scene& scene, const std::string& part) {
  for (const std::string& w : scene.warnings)
    if (w.find(part) != std::string::npos) return true;
  return false;
}

void expect_near(Vec3f a, Vec3f b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// ---- Bundled samples ----

TEST(GltfLoaderTest, AnimatedTriangleLoadsWithDefaultCamera) {
  auto loaded = load_gltf_scene(sample_path("AnimatedTriangle/AnimatedTriangle.gltf"), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  const Scene& scene = loaded->scene;
  ASSERT_EQ(scene.shapes.size(), 1u);
  EXPECT_EQ(scene.shapes[0].id, "node0");
  EXPECT_EQ(scene.shapes[0].mesh->triangle_count(), 1u);
  ASSERT_EQ(loaded->animation.tracks.size(), 1u);
  EXPECT_EQ(loaded->animation.tracks[0].target, "node0");
  EXPECT_TRUE(has_warning(scene, "default camera"));
  // The default camera looks at the triangle from +z.
  expect_near(scene.camera.to_world.vector(Vec3f(0, 0, 1)), Vec3f(0, 0, -1));
  // No material: glTF's default (metallic 1, roughness 1) -> rough conductor.
  EXPECT_EQ(scene.bsdfs[size_t(scene.shapes[0].bsdf)].type, BsdfType::kRoughConductor);
}

TEST(GltfLoaderTest, AnimatedCubeRotatesAndHasTexturedMaterial) {
  auto loaded = load_gltf_scene(sample_path("AnimatedCube/AnimatedCube.gltf"), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  const Scene& scene = loaded->scene;
  ASSERT_EQ(scene.shapes.size(), 1u);
  EXPECT_EQ(scene.shapes[0].id, "AnimatedCube");
  ASSERT_EQ(loaded->animation.tracks.size(), 1u);
  const Track& track = loaded->animation.tracks[0];
  EXPECT_EQ(track.target, "AnimatedCube");
  Transform t0 = evaluate_track(track, 0.0), t1 = evaluate_track(track, track.keys.back().time * 0.3);
  Vec3f a = t0.vector(Vec3f(1, 0, 0)), b = t1.vector(Vec3f(1, 0, 0));
  EXPECT_GT(length(a - b), 0.1f);  // it turned
  EXPECT_NEAR(length(b), 1.0f, 1e-5f);  // and only turned
  expect_near(t1.point(Vec3f(0.0f)), Vec3f(0.0f));
  const Bsdf& bsdf = scene.bsdfs[size_t(scene.shapes[0].bsdf)];
  const Texture& base = bsdf.type == BsdfType::kRoughPlastic || bsdf.type == BsdfType::kPlastic ? bsdf.reflectance
                                                                                                 : bsdf.specular_reflectance;
  EXPECT_EQ(base.type, TextureType::kBitmap);
  ASSERT_TRUE(base.bitmap);
  EXPECT_EQ(base.bitmap->width(), 128);
  EXPECT_TRUE(has_warning(scene, "metallicRoughnessTexture"));
  EXPECT_FALSE(scene.shapes[0].mesh->uvs.empty());
}

TEST(GltfLoaderTest, CesiumMilkTruckWheelsFollowTheirMatrixParents) {
  const std::string path = std::string(GDVR_SOURCE_DIR) + "/scenes/gltf/CesiumMilkTruck/CesiumMilkTruck.gltf";
  auto loaded = load_gltf_scene(path, LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  EXPECT_EQ(loaded->scene.shapes.size(), 5u);  // 3 truck primitives + 2 wheels
  ASSERT_EQ(loaded->animation.tracks.size(), 2u);
  for (const Track& t : loaded->animation.tracks) {
    // A wheel spins about its axle: its centre stays where its matrix parent puts it.
    Vec3f c0 = evaluate_track(t, 0.0).point(Vec3f(0.0f)), c1 = evaluate_track(t, 0.5).point(Vec3f(0.0f));
    expect_near(c0, c1, 1e-5f);
    EXPECT_NE(evaluate_track(t, 0.0), evaluate_track(t, 0.5));
  }
}

// ---- Synthetic features ----

TEST(GltfLoaderTest, GlbAndGltfGiveTheSameScene) {
  SyntheticGltf g;
  g.doc["nodes"][0]["translation"] = {1, 2, 3};
  fs::path dir = temp_dir("glb");
  auto a = load_gltf_scene(g.write(dir), LoadOptions());
  auto b = load_gltf_scene(g.write_glb(dir), LoadOptions());
  ASSERT_TRUE(a.ok()) << a.status().to_string();
  ASSERT_TRUE(b.ok()) << b.status().to_string();
  ASSERT_EQ(b->scene.shapes.size(), 1u);
  EXPECT_EQ(a->scene.shapes[0].to_world, b->scene.shapes[0].to_world);
  EXPECT_EQ(a->scene.shapes[0].mesh->positions.size(), b->scene.shapes[0].mesh->positions.size());
  expect_near(b->scene.shapes[0].to_world.point(Vec3f(0.0f)), Vec3f(1, 2, 3));
}

TEST(GltfLoaderTest, MatrixNodesAndUniqueIds) {
  SyntheticGltf g;
  // Column-major matrix: translation (5, 0, 0); a child named like its parent.
  g.doc["nodes"][0]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1};
  g.doc["nodes"].push_back({{"name", "tri"}, {"mesh", 0}, {"translation", {0, 1, 0}}});
  g.doc["nodes"][0]["children"] = {1};
  fs::path dir = temp_dir("matrix");
  auto loaded = load_gltf_scene(g.write(dir), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  ASSERT_EQ(loaded->scene.shapes.size(), 2u);
  EXPECT_EQ(loaded->scene.shapes[0].id, "tri");
  EXPECT_EQ(loaded->scene.shapes[1].id, "tri.1");
  expect_near(loaded->scene.shapes[1].to_world.point(Vec3f(0.0f)), Vec3f(5, 1, 0));
  EXPECT_EQ(loaded->scene.shapes[0].mesh, loaded->scene.shapes[1].mesh);  // shared, not copied
}

TEST(GltfLoaderTest, CameraConvertsFrameFovAndAnimates) {
  SyntheticGltf g;
  g.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}, {"zfar", 100}, {"aspectRatio", 2.0}}}}};
  int cam = g.add_node({{"name", "cam"}, {"camera", 0}, {"translation", {0, 0, 5}}});
  g.animate(cam, "translation", "LINEAR", {0, 1}, {0, 0, 5, 2, 0, 5});
  fs::path dir = temp_dir("camera");
  auto loaded = load_gltf_scene(g.write(dir), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  const Camera& c = loaded->scene.camera;
  EXPECT_EQ(c.id, "cam");
  EXPECT_NEAR(c.fov, 0.5 * 180.0 / 3.14159265358979, 1e-4);
  EXPECT_EQ(c.fov_axis, FovAxis::kY);
  EXPECT_FLOAT_EQ(c.near_clip, 0.1f);
  EXPECT_FLOAT_EQ(c.far_clip, 100.0f);
  EXPECT_EQ(loaded->scene.defaults.height, loaded->scene.defaults.width / 2);
  EXPECT_FALSE(has_warning(loaded->scene, "default camera"));
  // glTF cameras look along -z with +x to the right; gdvr's +x is the image's left.
  expect_near(c.to_world.vector(Vec3f(0, 0, 1)), Vec3f(0, 0, -1));
  expect_near(c.to_world.vector(Vec3f(1, 0, 0)), Vec3f(-1, 0, 0));
  expect_near(c.to_world.vector(Vec3f(0, 1, 0)), Vec3f(0, 1, 0));
  Scene scene = loaded->scene;
  ASSERT_TRUE(apply_animation(loaded->animation, 0.5, &scene).ok());
  expect_near(scene.camera.to_world.point(Vec3f(0.0f)), Vec3f(1, 0, 5));
  // A job's "sensor" track composes: it comes after the file's and wins.
  Animation with_job = loaded->animation;
  Track sensor;
  sensor.target = "sensor";
  sensor.keys.push_back(Keyframe{0.0, Transform::translate(Vec3f(0, 7, 0))});
  with_job.tracks.push_back(sensor);
  ASSERT_TRUE(validate_animation(with_job, loaded->scene).ok());
  ASSERT_TRUE(apply_animation(with_job, 0.5, &scene).ok());
  expect_near(scene.camera.to_world.point(Vec3f(0.0f)), Vec3f(0, 7, 0));
}

TEST(GltfLoaderTest, PunctualLightsMapOntoEmitters) {
  SyntheticGltf g;
  g.doc["extensionsUsed"] = {"KHR_lights_punctual"};
  g.doc["extensions"]["KHR_lights_punctual"]["lights"] = {
      {{"type", "point"}, {"color", {1, 0.5, 0.25}}, {"intensity", 10}},
      {{"type", "spot"}, {"intensity", 3}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.4}}}},
      {{"type", "directional"}, {"intensity", 2}, {"range", 5}}};
  g.add_node({{"name", "bulb"}, {"translation", {1, 2, 3}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  // Rotated -90 degrees about x: glTF's -z (the light's direction) becomes -y.
  const double s = std::sqrt(0.5);
  g.add_node({{"name", "spot"}, {"rotation", {-s, 0, 0, s}}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
  int sun = g.add_node({{"name", "sun"}, {"rotation", {-s, 0, 0, s}}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
  g.animate(sun, "translation", "STEP", {0, 1}, {0, 0, 0, 0, 1, 0});
  fs::path dir = temp_dir("lights");
  auto loaded = load_gltf_scene(g.write(dir), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  const auto& em = loaded->scene.emitters;
  ASSERT_EQ(em.size(), 3u);
  EXPECT_EQ(em[0].type, EmitterType::kPoint);
  EXPECT_EQ(em[0].id, "bulb");
  EXPECT_FLOAT_EQ(em[0].intensity.g, 5.0f);  // 1 cd -> 1 W/sr
  expect_near(em[0].to_world.point(Vec3f(0.0f)), Vec3f(1, 2, 3));
  EXPECT_EQ(em[1].type, EmitterType::kSpot);
  EXPECT_NEAR(em[1].cutoff_angle, 0.4 * 180 / 3.14159265358979, 1e-4);
  EXPECT_NEAR(em[1].beam_width, 0.2 * 180 / 3.14159265358979, 1e-4);
  expect_near(em[1].to_world.vector(Vec3f(0, 0, 1)), Vec3f(0, -1, 0));
  EXPECT_EQ(em[2].type, EmitterType::kDirectional);
  EXPECT_FLOAT_EQ(em[2].irradiance.r, 2.0f);  // 1 lx -> 1 W/m^2
  expect_near(em[2].to_world.vector(Vec3f(0, 0, 1)), Vec3f(0, -1, 0));
  EXPECT_TRUE(has_warning(loaded->scene, "range is ignored"));
  ASSERT_EQ(loaded->animation.tracks.size(), 1u);
  EXPECT_EQ(loaded->animation.tracks[0].target, "sun");
}

TEST(GltfLoaderTest, MaterialsMapOntoBsdfsAndEmitters) {
  SyntheticGltf g;
  g.doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
  g.doc["materials"] = {
      {{"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.6, 0.3, 1}}, {"metallicFactor", 1.0}, {"roughnessFactor", 0.5}}}},
      {{"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.4, 0.6, 1}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.0}}},
       {"doubleSided", true}},
      {{"emissiveFactor", {1, 0.5, 0.25}}, {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4}}}}}}};
  g.doc["meshes"].push_back({{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"material", 1}}}}});
  g.doc["meshes"].push_back({{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"material", 2}}}}});
  g.doc["meshes"][0]["primitives"][0]["material"] = 0;
  g.add_node({{"mesh", 1}});
  g.add_node({{"name", "lamp"}, {"mesh", 2}});
  fs::path dir = temp_dir("materials");
  auto loaded = load_gltf_scene(g.write(dir), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  const Scene& scene = loaded->scene;
  ASSERT_EQ(scene.shapes.size(), 3u);
  const Bsdf& metal = scene.bsdfs[size_t(scene.shapes[0].bsdf)];
  EXPECT_EQ(metal.type, BsdfType::kRoughConductor);
  EXPECT_EQ(metal.distribution, MicrofacetType::kGGX);
  EXPECT_FLOAT_EQ(metal.alpha_u, 0.25f);  // roughness^2
  EXPECT_FLOAT_EQ(metal.specular_reflectance.value.g, 0.6f);
  const Bsdf& plastic = scene.bsdfs[size_t(scene.shapes[1].bsdf)];
  EXPECT_EQ(plastic.type, BsdfType::kPlastic);  // roughness 0: the smooth variant
  EXPECT_TRUE(plastic.two_sided);
  EXPECT_FLOAT_EQ(plastic.reflectance.value.b, 0.6f);
  EXPECT_FLOAT_EQ(plastic.int_ior, 1.5f);
  EXPECT_EQ(scene.shapes[0].emitter, -1);
  ASSERT_GE(scene.shapes[2].emitter, 0);
  const Emitter& area = scene.emitters[size_t(scene.shapes[2].emitter)];
  EXPECT_EQ(area.type, EmitterType::kArea);
  EXPECT_EQ(area.shape, 2);
  EXPECT_FLOAT_EQ(area.radiance.r, 4.0f);
  EXPECT_FLOAT_EQ(area.radiance.b, 1.0f);
}

// ---- Rejections: each error names the file and the item ----

void expect_error(const Expected<LoadedScene>& r, StatusCode code, const std::vector<std::string>& parts) {
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), code) << r.status().to_string();
  for (const std::string& p : parts) EXPECT_NE(r.status().message().find(p), std::string::npos) << r.status().message();
}

TEST(GltfLoaderTest, RejectsSkinning) {
  SyntheticGltf g;
  g.doc["nodes"][0]["name"] = "skinned";
  g.doc["nodes"][0]["skin"] = 0;
  g.doc["skins"] = {{{"joints", {0}}}};
  fs::path dir = temp_dir("skin");
  expect_error(load_gltf_scene(g.write(dir), LoadOptions()), StatusCode::kUnimplemented, {"scene.gltf", "skinned", "skinning"});
}

TEST(GltfLoaderTest, RejectsMorphTargets) {
  SyntheticGltf g;
  g.doc["meshes"][0]["primitives"][0]["targets"] = {{{"POSITION", 0}}};
  fs::path dir = temp_dir("morph");
  expect_error(load_gltf_scene(g.write(dir), LoadOptions()), StatusCode::kUnimplemented, {"scene.gltf", "triangle", "morph targets"});
}

TEST(GltfLoaderTest, RejectsOrthographicCamerasAndLinePrimitives) {
  fs::path dir = temp_dir("ortho");
  SyntheticGltf ortho;
  ortho.doc["cameras"] = {{{"type", "orthographic"}, {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"znear", 0.1}, {"zfar", 10}}}}};
  ortho.add_node({{"camera", 0}});
  expect_error(load_gltf_scene(ortho.write(dir), LoadOptions()), StatusCode::kUnimplemented, {"orthographic"});
  SyntheticGltf lines;
  lines.doc["meshes"][0]["primitives"][0]["mode"] = 1;
  expect_error(load_gltf_scene(lines.write(dir), LoadOptions()), StatusCode::kUnimplemented, {"triangle", "LINES"});
}

TEST(GltfLoaderTest, RequiredUnknownExtensionIsAnErrorOptionalOneAWarning) {
  fs::path dir = temp_dir("ext");
  SyntheticGltf g;
  g.doc["extensionsUsed"] = {"KHR_texture_transform"};
  auto ok = load_gltf_scene(g.write(dir), LoadOptions());
  ASSERT_TRUE(ok.ok()) << ok.status().to_string();
  EXPECT_TRUE(has_warning(ok->scene, "KHR_texture_transform"));
  g.doc["extensionsRequired"] = {"KHR_texture_transform"};
  expect_error(load_gltf_scene(g.write(dir), LoadOptions()), StatusCode::kUnimplemented, {"scene.gltf", "KHR_texture_transform"});
}

TEST(GltfLoaderTest, MalformedJsonAndMissingFilesAreClearErrors) {
  fs::path dir = temp_dir("malformed");
  std::ofstream(dir / "bad.gltf") << "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [";
  expect_error(load_gltf_scene((dir / "bad.gltf").string(), LoadOptions()), StatusCode::kInvalidArgument, {"bad.gltf"});

  SyntheticGltf g;
  Json d = g.doc;
  d["buffers"] = {{{"byteLength", g.bin.size()}, {"uri", "missing.bin"}}};
  std::ofstream(dir / "nobuf.gltf") << d.dump();
  expect_error(load_gltf_scene((dir / "nobuf.gltf").string(), LoadOptions()), StatusCode::kNotFound, {"nobuf.gltf", "missing.bin"});

  expect_error(load_gltf_scene((dir / "absent.gltf").string(), LoadOptions()), StatusCode::kNotFound, {"absent.gltf"});
}

TEST(GltfLoaderTest, NonFiniteAccessorDataIsAnError) {
  fs::path dir = temp_dir("nan");
  SyntheticGltf g;
  float nan = std::nanf("");
  std::memcpy(g.bin.data() + 4, &nan, 4);  // vertex 0, y
  expect_error(load_gltf_scene(g.write(dir), LoadOptions()), StatusCode::kInvalidArgument,
               {"scene.gltf", "POSITION", "not finite"});
  SyntheticGltf a;
  a.animate(0, "translation", "LINEAR", {0, 1}, {0, 0, 0, std::numeric_limits<float>::infinity(), 0, 0});
  expect_error(load_gltf_scene(a.write(dir), LoadOptions()), StatusCode::kInvalidArgument, {"animations[0]", "not finite"});
}

TEST(GltfLoaderTest, AnimatedMatrixNodeIsAnError) {
  fs::path dir = temp_dir("matrix_anim");
  SyntheticGltf g;
  g.doc["nodes"][0]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  g.animate(0, "translation", "LINEAR", {0, 1}, {0, 0, 0, 1, 0, 0});
  expect_error(load_gltf_scene(g.write(dir), LoadOptions()), StatusCode::kInvalidArgument, {"tri", "matrix"});
}

// ---- Through the job runner ----

TEST(GltfLoaderTest, RendersThroughTheJobRunnerWithAnAddedLight) {
  // BoxAnimated plus a point light (KHR_lights_punctual) written beside its buffer.
  fs::path dir = temp_dir("render");
  fs::copy_file(sample_path("BoxAnimated/BoxAnimated0.bin"), dir / "BoxAnimated0.bin");
  Json doc = Json::parse(std::ifstream(sample_path("BoxAnimated/BoxAnimated.gltf")));
  doc["extensionsUsed"] = {"KHR_lights_punctual"};
  doc["extensions"]["KHR_lights_punctual"]["lights"] = {{{"type", "point"}, {"intensity", 200}}};
  doc["nodes"].push_back({{"name", "light"}, {"translation", {2, 6, 8}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  doc["scenes"][0]["nodes"].push_back(doc["nodes"].size() - 1);
  std::ofstream(dir / "lit.gltf") << doc.dump();

  JobSpec job;
  job.scene = (dir / "lit.gltf").string();
  job.frames = "0-1";
  job.fps = 1.0;  // frames 1 s apart: the inner box has moved up
  job.width = job.height = 16;
  job.spp = 2;
  job.outputs.previews = false;
  job.outputs.video_codec = "none";
  JobRunOptions options;
  options.threads = 2;
  std::vector<Image> frames;
  JobCallbacks callbacks;
  callbacks.on_frame_final = [&](const FrameOutput& out) { frames.push_back(out.image.find("")->image); };
  Status st = run_job(job, options, callbacks, nullptr);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(frames.size(), 2u);
  double sum = 0, diff = 0;
  for (size_t i = 0; i < frames[0].data().size(); ++i) {
    ASSERT_TRUE(std::isfinite(frames[0].data()[i]) && std::isfinite(frames[1].data()[i]));
    sum += frames[0].data()[i];
    diff += std::abs(frames[0].data()[i] - frames[1].data()[i]);
  }
  EXPECT_GT(sum, 0.0);   // lit
  EXPECT_GT(diff, 0.0);  // and different
}

// glTF's camera frame (+x right, +y up, looking down -z) survives the
// conversion: an emissive triangle right of and above the view axis lands in
// the image's top-right quadrant.
TEST(GltfLoaderTest, CameraImageOrientationMatchesGltf) {
  SyntheticGltf g;
  g.doc["materials"] = {{{"emissiveFactor", {1, 1, 1}}}};
  g.doc["meshes"][0]["primitives"][0]["material"] = 0;
  g.doc["nodes"][0]["translation"] = {0.5, 0.5, 0};  // triangle spans x, y in [0.5, 1.5]
  g.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 1.0}, {"znear", 0.01}}}}};
  g.add_node({{"name", "cam"}, {"camera", 0}, {"translation", {0, 0, 3}}});
  fs::path dir = temp_dir("orientation");
  JobSpec job;
  job.scene = g.write(dir);
  job.width = job.height = 16;
  job.spp = 4;
  job.outputs.previews = false;
  job.outputs.video_codec = "none";
  JobRunOptions options;
  options.threads = 2;
  Image frame;
  JobCallbacks callbacks;
  callbacks.on_frame_final = [&](const FrameOutput& out) { frame = out.image.find("")->image; };
  Status st = run_job(job, options, callbacks, nullptr);
  ASSERT_TRUE(st.ok()) << st.to_string();
  double quadrant[2][2] = {{0, 0}, {0, 0}};  // [top/bottom][left/right]
  for (int y = 0; y < frame.height(); ++y)
    for (int x = 0; x < frame.width(); ++x) quadrant[y < 8 ? 0 : 1][x < 8 ? 0 : 1] += frame.at(x, y, 0);
  EXPECT_GT(quadrant[0][1], 1.0);
  EXPECT_EQ(quadrant[0][0], 0.0);
  EXPECT_EQ(quadrant[1][0], 0.0);
  EXPECT_EQ(quadrant[1][1], 0.0);
}

}  // namespace
}  // namespace gdvr
