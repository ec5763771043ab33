// The shading frame's orientation around the normal, which anisotropic BSDFs
// depend on: along dp/du as Mitsuba 3 defines it per shape (a rectangle's
// x axis, a sphere's d/dphi, a mesh's uv parametrization), so that a scene's
// anisotropic highlights run the way its author saw them in Mitsuba.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/render/frame_scene.h"
#include "tests/core/render/xml_scene.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr {
namespace {

std::string one_shape_xml(const std::string& shape, const std::string& alphas) {
  return R"(<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
  <emitter type="constant"/>
  )" + shape + R"(<bsdf type="roughconductor">)" + alphas + R"(</bsdf></shape>
</scene>)";
}

const char* kAnisotropic = R"(<float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/>)";
const char* kIsotropic = R"(<float name="alpha" value="0.05"/>)";

using Loaded = test::XmlScene;
Loaded load(const std::string& xml) { return test::load_xml_scene(xml); }

void expect_near(Vec3f a, Vec3f b, const char* what) {
  EXPECT_NEAR(a.x, b.x, 1e-4f) << what;
  EXPECT_NEAR(a.y, b.y, 1e-4f) << what;
  EXPECT_NEAR(a.z, b.z, 1e-4f) << what;
}

void expect_orthonormal(const Frame& f) {
  EXPECT_NEAR(length(f.s), 1.0f, 1e-5f);
  EXPECT_NEAR(length(f.t), 1.0f, 1e-5f);
  EXPECT_NEAR(dot(f.s, f.n), 0.0f, 1e-5f);
  expect_near(cross(f.s, f.t), f.n, "s x t = n");
}

TEST(ShadingFrameTest, RectangleFrameFollowsItsXAxis) {
  auto l = load(one_shape_xml(
      R"(<shape type="rectangle"><transform name="to_world"><rotate z="1" angle="30"/></transform>)", kAnisotropic));
  ASSERT_TRUE(l.scene);
  SurfaceInteraction si;
  ASSERT_TRUE(l.scene->intersect(Ray{{0.1f, 0.2f, 1.0f}, {0, 0, -1}, 0, kInfinity}, &si));
  const float c = std::cos(float(M_PI) / 6), s = std::sin(float(M_PI) / 6);
  expect_near(si.sh_frame.s, Vec3f(c, s, 0), "s along the rotated x axis");
  expect_orthonormal(si.sh_frame);
}

TEST(ShadingFrameTest, SphereFrameFollowsDPhi) {
  auto l = load(one_shape_xml(R"(<shape type="sphere">)", kAnisotropic));
  ASSERT_TRUE(l.scene);
  SurfaceInteraction si;
  ASSERT_TRUE(l.scene->intersect(Ray{{3, 0, 0}, {-1, 0, 0}, 0, kInfinity}, &si));
  expect_near(si.sh_frame.s, Vec3f(0, 1, 0), "at +x");
  ASSERT_TRUE(l.scene->intersect(Ray{{0, 3, 0.2f}, {0, -1, 0}, 0, kInfinity}, &si));
  EXPECT_NEAR(si.sh_frame.s.x, -1.0f, 1e-3f) << "at +y";
  expect_orthonormal(si.sh_frame);
}

// A cube is a mesh with uvs: each face's frame follows its u direction, and
// a turn of the cube turns the frame with it.
TEST(ShadingFrameTest, MeshFrameFollowsItsUvParametrization) {
  auto straight = load(one_shape_xml(R"(<shape type="cube">)", kAnisotropic));
  auto turned = load(one_shape_xml(
      R"(<shape type="cube"><transform name="to_world"><rotate z="1" angle="90"/></transform>)", kAnisotropic));
  ASSERT_TRUE(straight.scene && turned.scene);
  SurfaceInteraction a, b;
  ASSERT_TRUE(straight.scene->intersect(Ray{{0.1f, 0.2f, 3}, {0, 0, -1}, 0, kInfinity}, &a));
  ASSERT_TRUE(turned.scene->intersect(Ray{{0.1f, 0.2f, 3}, {0, 0, -1}, 0, kInfinity}, &b));
  expect_near(a.sh_frame.n, Vec3f(0, 0, 1), "top face");
  EXPECT_NEAR(std::abs(a.sh_frame.s.z), 0.0f, 1e-5f);
  // Turned by 90 degrees about z: s turns with it.
  expect_near(b.sh_frame.s, Vec3f(-a.sh_frame.s.y, a.sh_frame.s.x, 0), "turned with the cube");
  expect_orthonormal(b.sh_frame);
}

// An isotropic BSDF does not see the orientation: its frame is built from
// the normal alone (the cheaper Frame(n)).
TEST(ShadingFrameTest, IsotropicSurfacesKeepTheNormalOnlyFrame) {
  auto l = load(one_shape_xml(
      R"(<shape type="rectangle"><transform name="to_world"><rotate z="1" angle="30"/></transform>)", kIsotropic));
  ASSERT_TRUE(l.scene);
  SurfaceInteraction si;
  ASSERT_TRUE(l.scene->intersect(Ray{{0.1f, 0.2f, 1.0f}, {0, 0, -1}, 0, kInfinity}, &si));
  const Frame f(si.sh_frame.n);
  expect_near(si.sh_frame.s, f.s, "Frame(n)");
}

}  // namespace
}  // namespace gdvr
