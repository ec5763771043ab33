// Mitsuba 0.x scene files, upgraded as Mitsuba 3 upgrades them on load: the
// name rules on their own, the loader on small 0.x files, and Bitterli's
// public veach-mis in its original Mitsuba 0.5 form against its 3.0 form.
#include "core/scene/mitsuba_upgrade.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

std::string scene_path(const std::string& rel) { return std::string(GDVR_SOURCE_DIR) + "/scenes/" + rel; }

bool has_warning(const Scene& s, const std::string& needle) {
  for (const std::string& w : s.warnings)
    if (w.find(needle) != std::string::npos) return true;
  return false;
}

std::string all_warnings(const Scene& s) {
  std::string out;
  for (const std::string& w : s.warnings) out += w + "\n";
  return out;
}

void expect_rgb_eq(Rgb a, Rgb b, const std::string& what) {
  EXPECT_EQ(a.r, b.r) << what;
  EXPECT_EQ(a.g, b.g) << what;
  EXPECT_EQ(a.b, b.b) << what;
}

// ---- The rules on their own ----

TEST(MitsubaUpgrade, CamelCaseNamesBecomeSnakeCase) {
  const std::pair<const char*, const char*> cases[] = {
      {"maxDepth", "max_depth"},
      {"rrDepth", "rr_depth"},
      {"hideEmitters", "hide_emitters"},
      {"intIOR", "int_ior"},
      {"extIOR", "ext_ior"},
      {"toWorld", "to_world"},
      {"fovAxis", "fov_axis"},
      {"focusDistance", "focus_distance"},
      {"sampleCount", "sample_count"},
      {"diffuseReflectance", "diffuse_reflectance"},
      {"specularReflectance", "specular_reflectance"},
      {"highQualityEdges", "high_quality_edges"},
      {"alphaU", "alpha_u"},
      // Already snake_case, all capitals, or no lowercase-uppercase pair: unchanged.
      {"max_depth", "max_depth"},
      {"reflectance", "reflectance"},
      {"IOR", "IOR"},
      {"B", "B"},
      {"bsdf_0", "bsdf_0"},
      // Each lowercase-uppercase pair starts a word (Mitsuba 3.9's rule).
      {"aBcD", "a_bc_d"},
  };
  for (const auto& [in, out] : cases) EXPECT_EQ(camel_to_snake_case(in), out) << in;
}

TEST(MitsubaUpgrade, SceneVersions) {
  SceneVersion v;
  ASSERT_TRUE(parse_scene_version("0.5.0", &v));
  EXPECT_TRUE(v.is_legacy());
  EXPECT_EQ(v.minor, 5u);
  ASSERT_TRUE(parse_scene_version("0.6.0", &v));
  EXPECT_TRUE(v.is_legacy());
  ASSERT_TRUE(parse_scene_version("1.9.9", &v));
  EXPECT_TRUE(v.is_legacy());
  ASSERT_TRUE(parse_scene_version("2.0.0", &v));
  EXPECT_FALSE(v.is_legacy());
  ASSERT_TRUE(parse_scene_version("3.0.0", &v));
  EXPECT_FALSE(v.is_legacy());
  ASSERT_TRUE(parse_scene_version("0.5.0-dev", &v));  // as Mitsuba's stoul
  EXPECT_EQ(v.patch, 0u);
  for (const char* bad : {"", "0.5", "3", "3.0.0.1", "abc", "a.b.c", "-1.0.0"})
    EXPECT_FALSE(parse_scene_version(bad, &v)) << bad;
}

// ---- The loader on small 0.x files ----

class MitsubaLoaderLegacyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) / (std::string("gdvr_legacy_") + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  Expected<Scene> load_version(const std::string& version, const std::string& body) {
    return load_mitsuba_scene(write("scene.xml", "<scene version=\"" + version + "\">\n" + body + "\n</scene>\n"), {});
  }
  fs::path dir_;
};

TEST_F(MitsubaLoaderLegacyTest, OldNamesLoad) {
  auto s = load_version("0.5.0", R"(
  <integrator type="path">
    <integer name="maxDepth" value="7"/>
    <integer name="rrDepth" value="3"/>
    <boolean name="hideEmitters" value="true"/>
  </integrator>
  <sensor type="perspective">
    <float name="fov" value="30"/>
    <string name="fovAxis" value="y"/>
    <float name="nearClip" value="0.5"/>
    <float name="farClip" value="500"/>
    <float name="focusDistance" value="4"/>
    <transform name="toWorld">
      <lookAt origin="1, 2, 3" target="1, 2, 4" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sampleCount" value="9"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="40"/>
      <integer name="height" value="30"/>
      <string name="pixelFormat" value="rgb"/>
    </film>
  </sensor>
  <shape type="sphere">
    <bsdf type="dielectric">
      <float name="intIOR" value="1.7"/>
      <float name="extIOR" value="1.1"/>
      <rgb name="specularReflectance" value="0.9"/>
    </bsdf>
  </shape>
  <shape type="sphere">
    <bsdf type="roughplastic">
      <rgb name="diffuseReflectance" value="0.1, 0.2, 0.3"/>
      <float name="alpha" value="0.2"/>
    </bsdf>
  </shape>
  <shape type="sphere">
    <bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.4, 0.5, 0.6"/></bsdf>
  </shape>)");
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  EXPECT_EQ(s->defaults.max_depth, 7);
  EXPECT_EQ(s->defaults.rr_depth, 3);
  EXPECT_TRUE(s->defaults.hide_emitters);
  EXPECT_EQ(s->defaults.spp, 9);
  EXPECT_EQ(s->defaults.width, 40);
  EXPECT_EQ(s->camera.fov_axis, FovAxis::kY);
  EXPECT_FLOAT_EQ(s->camera.near_clip, 0.5f);
  EXPECT_FLOAT_EQ(s->camera.far_clip, 500.0f);
  // <lookAt> read as <lookat>: the camera sits at the origin given.
  Vec3f o = s->camera.to_world.point(Vec3f(0.0f));
  EXPECT_NEAR(o.x, 1.0f, 1e-6f);
  EXPECT_NEAR(o.y, 2.0f, 1e-6f);
  EXPECT_NEAR(o.z, 3.0f, 1e-6f);
  ASSERT_EQ(s->shapes.size(), 3u);
  const Bsdf& glass = s->bsdfs[s->shapes[0].bsdf];
  EXPECT_EQ(glass.type, BsdfType::kDielectric);
  EXPECT_FLOAT_EQ(glass.int_ior, 1.7f);
  EXPECT_FLOAT_EQ(glass.ext_ior, 1.1f);
  EXPECT_FLOAT_EQ(glass.specular_reflectance.value.r, 0.9f);
  // plastic keeps diffuse_reflectance; only diffuse's becomes reflectance.
  const Bsdf& plastic = s->bsdfs[s->shapes[1].bsdf];
  EXPECT_EQ(plastic.type, BsdfType::kRoughPlastic);
  EXPECT_FLOAT_EQ(plastic.reflectance.value.b, 0.3f);
  const Bsdf& diffuse = s->bsdfs[s->shapes[2].bsdf];
  EXPECT_EQ(diffuse.type, BsdfType::kDiffuse);
  expect_rgb_eq(diffuse.reflectance.value, Rgb(0.4f, 0.5f, 0.6f), "diffuse reflectance");
  EXPECT_TRUE(has_warning(*s, "scene.xml:1: Mitsuba 0.5.0 file upgraded")) << all_warnings(*s);
}

TEST_F(MitsubaLoaderLegacyTest, Version3FileIsNotUpgraded) {
  auto s = load_version("3.0.0", R"(
  <integrator type="path">
    <integer name="maxDepth" value="7"/>
  </integrator>)");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.status().message().find("scene.xml:4:"), std::string::npos) << s.status().message();
  EXPECT_NE(s.status().message().find("unknown parameter 'maxDepth'"), std::string::npos) << s.status().message();
  // Nor is <lookAt> a 3.0 tag.
  s = load_version("2.0.0", R"(
  <sensor type="perspective">
    <transform name="to_world"><lookAt origin="0, 0, 0" target="0, 0, 1"/></transform>
  </sensor>)");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("scene.xml:4:"), std::string::npos) << s.status().message();
  EXPECT_NE(s.status().message().find("<lookAt>"), std::string::npos) << s.status().message();
}

TEST_F(MitsubaLoaderLegacyTest, UvOffsetAndScaleBecomeToUv) {
  // translate (0.25, -0.5) first, then scale (2, 3): the 3.0 form Mitsuba 3 makes.
  auto legacy = load_version("0.6.0", R"(
  <shape type="sphere">
    <bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <float name="uoffset" value="0.25"/>
        <float name="voffset" value="-0.5"/>
        <float name="uscale" value="2"/>
        <float name="vscale" value="3"/>
      </texture>
    </bsdf>
  </shape>
  <shape type="sphere">
    <bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <float name="uscale" value="4"/>
      </texture>
    </bsdf>
  </shape>)");
  ASSERT_TRUE(legacy.ok()) << legacy.status().to_string();
  auto modern = load_version("3.0.0", R"(
  <shape type="sphere">
    <bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <transform name="to_uv"><translate x="0.25" y="-0.5"/><scale x="2" y="3"/></transform>
      </texture>
    </bsdf>
  </shape>)");
  ASSERT_TRUE(modern.ok()) << modern.status().to_string();
  const UvTransform& t = legacy->bsdfs[legacy->shapes[0].bsdf].reflectance.to_uv;
  const UvTransform& m = modern->bsdfs[modern->shapes[0].bsdf].reflectance.to_uv;
  EXPECT_EQ(t.a, 2.0f);
  EXPECT_EQ(t.e, 3.0f);
  EXPECT_EQ(t.c, 0.5f);   // 2 * 0.25
  EXPECT_EQ(t.f, -1.5f);  // 3 * -0.5
  EXPECT_EQ(t.b, 0.0f);
  EXPECT_EQ(t.d, 0.0f);
  for (float UvTransform::*f : {&UvTransform::a, &UvTransform::b, &UvTransform::c, &UvTransform::d, &UvTransform::e,
                                &UvTransform::f})
    EXPECT_EQ(t.*f, m.*f);
  // Only uscale: v keeps its scale of one, no offset.
  const UvTransform& u = legacy->bsdfs[legacy->shapes[1].bsdf].reflectance.to_uv;
  EXPECT_EQ(u.a, 4.0f);
  EXPECT_EQ(u.e, 1.0f);
  EXPECT_EQ(u.c, 0.0f);
  EXPECT_EQ(u.f, 0.0f);
  EXPECT_EQ(legacy->bsdfs[legacy->shapes[0].bsdf].reflectance.type, TextureType::kCheckerboard);

  auto bad = load_version("0.5.0", R"(
  <texture type="checkerboard" id="t">
    <float name="uoffset" value="1 2"/>
  </texture>)");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("scene.xml:4:"), std::string::npos) << bad.status().message();
  EXPECT_NE(bad.status().message().find("uoffset"), std::string::npos) << bad.status().message();
}

TEST_F(MitsubaLoaderLegacyTest, ReservedIdsAreRenamed) {
  auto s = load_version("0.5.0", R"(
  <bsdf type="diffuse" id="_red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
  <shape type="sphere" id="_ball"><ref id="_red"/></shape>)");
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  ASSERT_EQ(s->shapes.size(), 1u);
  EXPECT_EQ(s->shapes[0].id, "ID_ball__UPGR");
  EXPECT_FLOAT_EQ(s->bsdfs[s->shapes[0].bsdf].reflectance.value.r, 0.8f);
  EXPECT_TRUE(has_warning(*s, "scene.xml:3: id '_red' renamed to 'ID_red__UPGR'")) << all_warnings(*s);
}

TEST_F(MitsubaLoaderLegacyTest, FilmAndSamplerBookkeepingIsIgnoredWithWarnings) {
  auto s = load_version("0.5.0", R"(
  <integrator type="path">
    <integer name="maxDepth" value="4"/>
    <boolean name="strictNormals" value="true"/>
  </integrator>
  <sensor type="perspective">
    <sampler type="ldsampler">
      <integer name="sampleCount" value="16"/>
      <integer name="dimension" value="4"/>
    </sampler>
    <film type="hdrfilm">
      <integer name="width" value="64"/>
      <integer name="height" value="48"/>
      <boolean name="banner" value="false"/>
      <boolean name="highQualityEdges" value="true"/>
      <boolean name="attachLog" value="false"/>
      <float name="gamma" value="2.2"/>
      <string name="fileFormat" value="png"/>
      <rfilter name="rfilter" type="box"/>
    </film>
  </sensor>)");
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  EXPECT_EQ(s->defaults.spp, 16);
  EXPECT_EQ(s->defaults.width, 64);
  EXPECT_EQ(s->defaults.max_depth, 4);
  std::string w = all_warnings(*s);
  EXPECT_TRUE(has_warning(*s, "scene.xml:3: integrator 'path': ignored 'strict_normals'")) << w;
  EXPECT_TRUE(has_warning(*s, "scene.xml:8: sampler 'ldsampler': ignored 'dimension'")) << w;
  EXPECT_TRUE(has_warning(*s, "scene.xml:12: film 'hdrfilm': ignored 'banner'")) << w;
  EXPECT_TRUE(has_warning(*s, "ignored 'high_quality_edges', 'attach_log', 'gamma'")) << w;

  // The 0.x-only ones stay errors in a Mitsuba 3 file (as in Mitsuba 3);
  // banner is accepted there too, as Mitsuba 3's hdrfilm does.
  auto modern = load_version("3.0.0", R"(
  <sensor type="perspective">
    <film type="hdrfilm"><boolean name="banner" value="false"/></film>
    <sampler type="ldsampler"><integer name="dimension" value="4"/></sampler>
  </sensor>)");
  ASSERT_FALSE(modern.ok());
  EXPECT_NE(modern.status().message().find("scene.xml:5:"), std::string::npos) << modern.status().message();
  EXPECT_NE(modern.status().message().find("unknown parameter 'dimension'"), std::string::npos)
      << modern.status().message();
}

TEST_F(MitsubaLoaderLegacyTest, ZeroXSamplersAndLdrFilm) {
  auto s = load_version("0.5.0", R"(
  <sensor type="perspective">
    <sampler type="sobol"><integer name="sampleCount" value="32"/><integer name="scramble" value="1"/></sampler>
    <film type="ldrfilm">
      <integer name="width" value="20"/>
      <integer name="height" value="10"/>
      <string name="tonemapMethod" value="gamma"/>
      <float name="exposure" value="1"/>
    </film>
  </sensor>)");
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  EXPECT_EQ(s->defaults.spp, 32);
  EXPECT_EQ(s->defaults.width, 20);
  EXPECT_TRUE(has_warning(*s, "sampler 'sobol' read for its sample_count only")) << all_warnings(*s);
  EXPECT_TRUE(has_warning(*s, "ldrfilm read as hdrfilm")) << all_warnings(*s);
  EXPECT_TRUE(has_warning(*s, "ignored 'exposure', 'tonemap_method'")) << all_warnings(*s);
  auto modern = load_version("3.0.0", R"(<sensor type="perspective"><sampler type="sobol"/></sensor>)");
  ASSERT_FALSE(modern.ok());
  EXPECT_NE(modern.status().message().find("unknown sampler type 'sobol'"), std::string::npos)
      << modern.status().message();
}

TEST_F(MitsubaLoaderLegacyTest, ConductorExteriorIor) {
  // Mitsuba 0.x divided a conductor's eta and k by extEta.
  auto s = load_version("0.5.0", R"(
  <shape type="sphere">
    <bsdf type="roughconductor">
      <rgb name="eta" value="0.2, 0.9, 1.1"/>
      <rgb name="k" value="4, 2.5, 2"/>
      <float name="extEta" value="2"/>
    </bsdf>
  </shape>
  <shape type="sphere">
    <bsdf type="conductor">
      <rgb name="eta" value="0.2, 0.9, 1.1"/>
      <rgb name="k" value="4, 2.5, 2"/>
      <float name="extEta" value="1"/>
    </bsdf>
  </shape>)");
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  const Bsdf& halved = s->bsdfs[s->shapes[0].bsdf];
  expect_rgb_eq(halved.eta, Rgb(0.1f, 0.45f, 0.55f), "eta / 2");
  expect_rgb_eq(halved.k, Rgb(2.0f, 1.25f, 1.0f), "k / 2");
  const Bsdf& same = s->bsdfs[s->shapes[1].bsdf];
  expect_rgb_eq(same.eta, Rgb(0.2f, 0.9f, 1.1f), "eta / 1");
  auto modern = load_version("3.0.0", R"(
  <bsdf type="conductor" id="c"><float name="ext_eta" value="1"/></bsdf>)");
  ASSERT_FALSE(modern.ok());
  EXPECT_NE(modern.status().message().find("unknown parameter 'ext_eta'"), std::string::npos)
      << modern.status().message();
}

TEST_F(MitsubaLoaderLegacyTest, EachIncludedFileIsUpgradedByItsOwnVersion) {
  write("old.xml", R"(<scene version="0.5.0">
  <bsdf type="diffuse" id="grey"><rgb name="diffuseReflectance" value="0.3"/></bsdf>
</scene>)");
  auto s = load_version("3.0.0", R"(
  <include filename="old.xml"/>
  <shape type="sphere"><ref id="grey"/></shape>
  <integrator type="path"><integer name="max_depth" value="5"/></integrator>)");
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  EXPECT_FLOAT_EQ(s->bsdfs[s->shapes[0].bsdf].reflectance.value.g, 0.3f);
  EXPECT_EQ(s->defaults.max_depth, 5);
  EXPECT_TRUE(has_warning(*s, "old.xml:1: Mitsuba 0.5.0 file upgraded")) << all_warnings(*s);

  // And the other way round: a 3.0 file included by a 0.5 one keeps its names.
  write("new.xml", R"(<scene version="3.0.0">
  <integrator type="path"><integer name="maxDepth" value="5"/></integrator>
</scene>)");
  auto bad = load_version("0.5.0", R"(<include filename="new.xml"/>)");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("new.xml:2:"), std::string::npos) << bad.status().message();
  EXPECT_NE(bad.status().message().find("unknown parameter 'maxDepth'"), std::string::npos) << bad.status().message();
}

TEST_F(MitsubaLoaderLegacyTest, InvalidVersionIsAnError) {
  auto s = load_version("0.5", "");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.status().message().find("scene.xml:1: invalid version number '0.5'"), std::string::npos)
      << s.status().message();
}

// ---- A public 0.5 scene against its 3.0 form ----

// Bitterli's veach-mis as published (Mitsuba 0.5: camelCase names, sobol
// sampler, strictNormals, extEta, film gamma and banner) and the 3.0
// conversion bundled beside it, with the 3.0 file's defaults set to the 0.5
// file's values (320x180, max_depth 1; 64 spp in both).
LoadOptions veach_mis_30_options() {
  LoadOptions o;
  o.params = {{"resx", "320"}, {"resy", "180"}, {"max_depth", "1"}};
  return o;
}

struct VeachMisPair {
  Expected<Scene> legacy = load_mitsuba_scene(scene_path("veach-mis/scene-v0.5.xml"), {});
  Expected<Scene> modern = load_mitsuba_scene(scene_path("veach-mis/scene.xml"), veach_mis_30_options());
};

void expect_same_bsdf(const Bsdf& a, const Bsdf& b, const std::string& what) {
  EXPECT_EQ(a.type, b.type) << what;
  EXPECT_EQ(a.two_sided, b.two_sided) << what;
  EXPECT_EQ(a.reflectance.type, TextureType::kConstant) << what;
  expect_rgb_eq(a.reflectance.value, b.reflectance.value, what + " reflectance");
  expect_rgb_eq(a.specular_reflectance.value, b.specular_reflectance.value, what + " specular_reflectance");
  expect_rgb_eq(a.eta, b.eta, what + " eta");
  expect_rgb_eq(a.k, b.k, what + " k");
  EXPECT_EQ(a.distribution, b.distribution) << what;
  EXPECT_EQ(a.alpha_u, b.alpha_u) << what;
  EXPECT_EQ(a.alpha_v, b.alpha_v) << what;
  EXPECT_EQ(a.sample_visible, b.sample_visible) << what;
}

TEST(MitsubaLoaderLegacyScene, VeachMis05LoadsAsIts30Form) {
  VeachMisPair p;
  ASSERT_TRUE(p.legacy.ok()) << p.legacy.status().to_string();
  ASSERT_TRUE(p.modern.ok()) << p.modern.status().to_string();
  const Scene& a = *p.legacy;
  const Scene& b = *p.modern;

  EXPECT_EQ(a.defaults.width, 320);
  EXPECT_EQ(a.defaults.height, 180);
  EXPECT_EQ(a.defaults.spp, 64);
  EXPECT_EQ(a.defaults.max_depth, 1);
  EXPECT_EQ(a.defaults.width, b.defaults.width);
  EXPECT_EQ(a.defaults.height, b.defaults.height);
  EXPECT_EQ(a.defaults.spp, b.defaults.spp);
  EXPECT_EQ(a.defaults.max_depth, b.defaults.max_depth);
  EXPECT_EQ(a.defaults.rr_depth, b.defaults.rr_depth);
  EXPECT_EQ(a.defaults.hide_emitters, b.defaults.hide_emitters);

  EXPECT_EQ(a.camera.fov, b.camera.fov);
  EXPECT_EQ(a.camera.fov_axis, b.camera.fov_axis);
  EXPECT_EQ(a.camera.near_clip, b.camera.near_clip);
  EXPECT_EQ(a.camera.far_clip, b.camera.far_clip);
  EXPECT_EQ(a.camera.to_world, b.camera.to_world);

  ASSERT_EQ(a.shapes.size(), 9u);
  ASSERT_EQ(a.shapes.size(), b.shapes.size());
  for (size_t i = 0; i < a.shapes.size(); ++i) {
    const Shape& sa = a.shapes[i];
    const Shape& sb = b.shapes[i];
    std::string what = "shape " + std::to_string(i) + " (" + sb.id + ")";
    EXPECT_EQ(sa.type, sb.type) << what;
    EXPECT_EQ(sa.to_world, sb.to_world) << what;
    EXPECT_EQ(sa.flip_normals, sb.flip_normals) << what;
    EXPECT_EQ(sa.face_normals, sb.face_normals) << what;
    ASSERT_EQ(bool(sa.mesh), bool(sb.mesh)) << what;
    if (sa.mesh) {
      EXPECT_EQ(sa.mesh->indices, sb.mesh->indices) << what;
      ASSERT_EQ(sa.mesh->positions.size(), sb.mesh->positions.size()) << what;
      for (size_t v = 0; v < sa.mesh->positions.size(); ++v)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(sa.mesh->positions[v][c], sb.mesh->positions[v][c]) << what;
    }
    ASSERT_GE(sa.bsdf, 0);
    ASSERT_GE(sb.bsdf, 0);
    expect_same_bsdf(a.bsdfs[sa.bsdf], b.bsdfs[sb.bsdf], what);
    ASSERT_EQ(sa.emitter >= 0, sb.emitter >= 0) << what;
  }
  ASSERT_EQ(a.emitters.size(), 3u);
  ASSERT_EQ(a.emitters.size(), b.emitters.size());
  for (size_t i = 0; i < a.emitters.size(); ++i) {
    std::string what = "emitter " + std::to_string(i);
    EXPECT_EQ(a.emitters[i].type, b.emitters[i].type) << what;
    EXPECT_EQ(a.emitters[i].shape, b.emitters[i].shape) << what;
    EXPECT_EQ(a.emitters[i].to_world, b.emitters[i].to_world) << what;
    expect_rgb_eq(a.emitters[i].radiance, b.emitters[i].radiance, what + " radiance");
  }
  // What was left out is said, not silent.
  std::string w = all_warnings(a);
  EXPECT_TRUE(has_warning(a, "scene-v0.5.xml:3: Mitsuba 0.5.0 file upgraded")) << w;
  EXPECT_TRUE(has_warning(a, "ignored 'strict_normals'")) << w;
  EXPECT_TRUE(has_warning(a, "sampler 'sobol' read for its sample_count only")) << w;
  EXPECT_TRUE(has_warning(a, "ignored 'banner'")) << w;
  EXPECT_TRUE(has_warning(a, "ignored 'gamma'")) << w;
}

TEST(MitsubaLoaderLegacyScene, VeachMis05RendersAsIts30Form) {
  VeachMisPair p;
  ASSERT_TRUE(p.legacy.ok()) << p.legacy.status().to_string();
  ASSERT_TRUE(p.modern.ok()) << p.modern.status().to_string();
  FrameRenderSettings settings;
  settings.width = 32;
  settings.height = 32;
  settings.spp = 4;
  settings.seed = 11;
  // The file's max_depth 1 shows only the lights; 3 also lights the plates
  // through their BSDFs (the depth the 3.0 form asks for by default).
  settings.path.max_depth = 3;
  settings.path.rr_depth = p.legacy->defaults.rr_depth;
  Image images[2];
  const Scene* scenes[2] = {&*p.legacy, &*p.modern};
  for (int i = 0; i < 2; ++i) {
    auto fs = FrameScene::create(*scenes[i], {});
    ASSERT_TRUE(fs.ok()) << fs.status().to_string();
    auto r = render_frame_pt(*fs.value(), settings, /* frame = */ 0, {});
    ASSERT_TRUE(r.ok()) << r.status().to_string();
    images[i] = std::move(r->color);
  }
  ASSERT_EQ(images[0].width(), 32);
  ASSERT_EQ(images[1].height(), 32);
  int differing = 0;
  double sum = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      for (int c = 0; c < 3; ++c) {
        differing += images[0].at(x, y, c) != images[1].at(x, y, c);
        sum += images[0].at(x, y, c);
      }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(sum, 0.0);  // not trivially equal
}

}  // namespace
}  // namespace gdvr
