// The feature buffers (core/render/feature_buffers.h) on scenes whose albedo,
// normal and depth are known: a plane facing the camera, the same seen in a
// mirror and through a pane of glass, emitters and the environment seen
// directly; and the same buffers whatever the thread count.
#include "core/render/feature_buffers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/render/perspective_camera.h"
#include "core/scene/mitsuba_loader.h"
#include "tests/core/render/xml_scene.h"

namespace gdvr {
namespace {

constexpr int kSize = 16;
constexpr float kCameraZ = 5.0f;

// A camera at (0, 0, 5) looking down -z at the origin, and `shapes`.
std::string scene_xml(const std::string& shapes) {
  return R"(<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
  </sensor>
)" + shapes + "\n</scene>";
}

// A 20 × 20 rectangle in the plane z = `z`, facing +z (or -z with `flip`).
std::string plane(float z, const std::string& bsdf, bool flip = false, const std::string& inside = "") {
  return "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"10\"/><translate z=\"" +
         std::to_string(z) + "\"/></transform>" + (flip ? "<boolean name=\"flip_normals\" value=\"true\"/>" : "") +
         bsdf + inside + "</shape>\n";
}

const char* const kPlaneColour = "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.2, 0.4, 0.6\"/></bsdf>";
const Rgb kPlaneAlbedo(0.2f, 0.4f, 0.6f);

using Loaded = test::XmlScene;
Loaded load(const std::string& xml) { return test::load_xml_scene(xml); }

FeatureBuffers features(const FrameScene& scene, int threads = 2, bool hide_emitters = false) {
  FrameRenderSettings frame;
  frame.width = frame.height = kSize;
  frame.seed = 11;
  frame.threads = threads;
  frame.path.hide_emitters = hide_emitters;
  auto f = render_feature_buffers(scene, frame, FeatureBufferSettings{}, nullptr);
  EXPECT_TRUE(f.ok()) << f.status().to_string();
  return f.ok() ? std::move(f.value()) : FeatureBuffers{};
}

Vec3f normal_at(const FeatureBuffers& f, int x, int y) {
  return {f.normal.at(x, y, 0), f.normal.at(x, y, 1), f.normal.at(x, y, 2)};
}

// The distance from the camera to the plane z = `z` along the ray through the
// pixel's centre: the depth of a pixel to within its angular size.
float distance_to_plane(const Camera& camera, int x, int y, float z) {
  const Ray r = PerspectiveCamera(camera, kSize, kSize).generate_ray({float(x) + 0.5f, float(y) + 0.5f});
  return (r.o.z - z) / -r.d.z;
}

void expect_rgb_near(Rgb got, Rgb want, float tolerance) {
  EXPECT_NEAR(got.r, want.r, tolerance);
  EXPECT_NEAR(got.g, want.g, tolerance);
  EXPECT_NEAR(got.b, want.b, tolerance);
}

TEST(FeatureBuffersTest, DiffusePlaneGivesItsReflectanceNormalAndDistance) {
  Loaded l = load(scene_xml(plane(0, kPlaneColour)));
  ASSERT_TRUE(l.scene);
  const FeatureBuffers f = features(*l.scene);
  ASSERT_EQ(f.albedo.width(), kSize);
  EXPECT_GE(f.rays, uint64_t(kSize * kSize * 16));
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      SCOPED_TRACE(std::to_string(x) + "," + std::to_string(y));
      expect_rgb_near(f.albedo.rgb(x, y), kPlaneAlbedo, 1e-6f);
      const Vec3f n = normal_at(f, x, y);
      EXPECT_NEAR(n.x, 0.0f, 1e-6f);
      EXPECT_NEAR(n.y, 0.0f, 1e-6f);
      EXPECT_NEAR(n.z, 1.0f, 1e-6f);
      // The nearest sample of the pixel: a little closer than its centre's.
      const float centre = distance_to_plane(l.desc.camera, x, y, 0.0f);
      EXPECT_LE(f.depth.at(x, y, 0), centre * 1.0001f);
      EXPECT_GE(f.depth.at(x, y, 0), kCameraZ * 0.9999f);
      EXPECT_NEAR(f.depth.at(x, y, 0), centre, centre * 0.01f);
    }
}

// A perfect mirror at z = 0 reflects the camera's rays back to a plane at
// z = 10 behind the camera: the mirror's pixels show that plane's albedo and
// normal, at the mirror's depth.
TEST(FeatureBuffersTest, MirrorShowsTheAlbedoAndNormalOfWhatItReflects) {
  const std::string mirror = "<bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/></bsdf>";
  const char* const behind = "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7, 0.5, 0.1\"/></bsdf>";
  Loaded l = load(scene_xml(plane(0, mirror) + plane(10, behind, /*flip=*/true)));
  ASSERT_TRUE(l.scene);
  const FeatureBuffers f = features(*l.scene);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      SCOPED_TRACE(std::to_string(x) + "," + std::to_string(y));
      expect_rgb_near(f.albedo.rgb(x, y), Rgb(0.7f, 0.5f, 0.1f), 1e-4f);
      const Vec3f n = normal_at(f, x, y);
      EXPECT_NEAR(n.z, -1.0f, 1e-5f);
      const float centre = distance_to_plane(l.desc.camera, x, y, 0.0f);
      EXPECT_NEAR(f.depth.at(x, y, 0), centre, centre * 0.01f);
    }
}

// A thin pane of glass at z = 2 in front of the plane, under a uniform sky of
// 0.5: each camera sample splits into the transmitted branch (the plane) and
// the reflected one (the sky), weighted by the pane's reflectance R (about
// 0.08 near normal incidence), with no noise: every channel and the normal
// agree on one R per pixel.
TEST(FeatureBuffersTest, PaneOfGlassBlendsWhatItTransmitsAndReflects) {
  const std::string glass = "<bsdf type=\"thindielectric\"/>";
  const std::string sky = "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.5\"/></emitter>\n";
  Loaded l = load(scene_xml(plane(0, kPlaneColour) + plane(2, glass) + sky));
  ASSERT_TRUE(l.scene);
  const FeatureBuffers f = features(*l.scene);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      SCOPED_TRACE(std::to_string(x) + "," + std::to_string(y));
      const Rgb a = f.albedo.rgb(x, y);
      const float reflectance = (a.r - kPlaneAlbedo.r) / (0.5f - kPlaneAlbedo.r);
      EXPECT_GT(reflectance, 0.06f);
      EXPECT_LT(reflectance, 0.1f);
      expect_rgb_near(a, kPlaneAlbedo * (1.0f - reflectance) + Rgb(0.5f) * reflectance, 1e-5f);
      const Vec3f n = normal_at(f, x, y);
      EXPECT_NEAR(n.z, 1.0f - reflectance, 1e-5f);
      // Depth is the pane's: the surface the camera sees first.
      const float centre = distance_to_plane(l.desc.camera, x, y, 2.0f);
      EXPECT_NEAR(f.depth.at(x, y, 0), centre, centre * 0.01f);
    }
}

TEST(FeatureBuffersTest, EmittersAndTheEnvironmentGiveTheirClampedRadiance) {
  {
    Loaded l = load(scene_xml("<emitter type=\"constant\"><rgb name=\"radiance\" value=\"2, 0.5, 0.25\"/></emitter>"));
    ASSERT_TRUE(l.scene);
    const FeatureBuffers f = features(*l.scene);
    expect_rgb_near(f.albedo.rgb(3, 5), Rgb(1.0f, 0.5f, 0.25f), 1e-6f);
    const Vec3f n = normal_at(f, 3, 5);
    EXPECT_EQ(n.x, 0.0f);
    EXPECT_EQ(n.y, 0.0f);
    EXPECT_EQ(n.z, 0.0f);
    EXPECT_EQ(f.depth.at(3, 5, 0), kMissDepth);
    // Hidden from the camera, the sky is black in the image and in the albedo.
    const FeatureBuffers hidden = features(*l.scene, 2, /*hide_emitters=*/true);
    expect_rgb_near(hidden.albedo.rgb(3, 5), Rgb(0.0f), 0.0f);
  }
  {
    const std::string light = "<emitter type=\"area\"><rgb name=\"radiance\" value=\"3, 0.2, 0.7\"/></emitter>";
    Loaded l = load(scene_xml(plane(0, kPlaneColour, false, light)));
    ASSERT_TRUE(l.scene);
    const FeatureBuffers f = features(*l.scene);
    expect_rgb_near(f.albedo.rgb(8, 8), Rgb(1.0f, 0.2f, 0.7f), 1e-6f);
    EXPECT_NEAR(normal_at(f, 8, 8).z, 1.0f, 1e-6f);
    // Hidden, the emitter shows its surface's albedo.
    const FeatureBuffers hidden = features(*l.scene, 2, /*hide_emitters=*/true);
    expect_rgb_near(hidden.albedo.rgb(8, 8), kPlaneAlbedo, 1e-6f);
  }
}

TEST(FeatureBuffersTest, SameBuffersWhateverTheThreadCount) {
  const std::string glass = "<bsdf type=\"dielectric\"/>";
  const std::string sphere =
      "<shape type=\"sphere\"><point name=\"center\" x=\"0.3\" y=\"0\" z=\"1\"/><float name=\"radius\" value=\"1\"/>" +
      glass + "</shape>\n";
  Loaded l = load(scene_xml(plane(0, kPlaneColour) + sphere +
                            "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.5\"/></emitter>"));
  ASSERT_TRUE(l.scene);
  const FeatureBuffers one = features(*l.scene, 1);
  const FeatureBuffers three = features(*l.scene, 3);
  EXPECT_EQ(one.albedo.data(), three.albedo.data());
  EXPECT_EQ(one.normal.data(), three.normal.data());
  EXPECT_EQ(one.depth.data(), three.depth.data());
  EXPECT_EQ(one.rays, three.rays);
  // Through the glass sphere the plane's colour still shows (not the glass's 1).
  const Rgb centre = one.albedo.rgb(kSize / 2, kSize / 2);
  EXPECT_LT(centre.r, 0.5f);
  EXPECT_GT(centre.b, centre.r);
}

TEST(FeatureBuffersTest, PatternGrowsWithTheJobsSamplesFromTwoByTwoToFourByFour) {
  EXPECT_EQ(feature_buffer_settings_for(1).strata, 2);  // a time budget's 1-spp passes
  EXPECT_EQ(feature_buffer_settings_for(8).strata, 2);
  EXPECT_EQ(feature_buffer_settings_for(9).strata, 3);
  EXPECT_EQ(feature_buffer_settings_for(16).strata, 4);
  EXPECT_EQ(feature_buffer_settings_for(4096).strata, 4);
  EXPECT_TRUE(feature_buffer_settings_for(0).validate().ok());
}

TEST(FeatureBuffersTest, LayersAreNamedAsCompositorsExpect) {
  FeatureBuffers f;
  f.albedo = Image(2, 2, 3);
  f.normal = Image(2, 2, 3);
  f.depth = Image(2, 2, 1);
  LayeredImage li;
  add_feature_layers(std::move(f), &li);
  ASSERT_EQ(li.layers.size(), 3u);
  EXPECT_EQ(li.find("albedo")->channels, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_EQ(li.find("N")->channels, (std::vector<std::string>{"X", "Y", "Z"}));
  EXPECT_EQ(li.find("Z")->channels, (std::vector<std::string>{"Z"}));
  LayeredImage copy;
  copy_feature_layers(li, &copy);
  EXPECT_EQ(copy.layers.size(), 3u);
}

}  // namespace
}  // namespace gdvr
