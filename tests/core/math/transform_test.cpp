#include "core/math/transform.h"

#include <gtest/gtest.h>

namespace gdvr {
namespace {

void expect_near(Vec3f a, Vec3f b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(TransformTest, InverseRoundTrips) {
  Transform t = Transform::translate({1, 2, 3}) * Transform::rotate({0, 1, 1}, 37) * Transform::scale({2, 3, 4});
  Vec3f p(0.3f, -1.2f, 5.0f);
  expect_near(t.inverse().point(t.point(p)), p);
}

TEST(TransformTest, RotateQuarterTurnAboutZ) { expect_near(Transform::rotate({0, 0, 1}, 90).vector({1, 0, 0}), {0, 1, 0}); }

TEST(TransformTest, LookAtMapsForwardToTarget) {
  Transform t;
  ASSERT_TRUE(Transform::look_at({278, 273, -800}, {278, 273, -799}, {0, 1, 0}, &t));
  expect_near(t.point({0, 0, 1}), {278, 273, -799});
  expect_near(t.vector({0, 1, 0}), {0, 1, 0});
  expect_near(t.vector({1, 0, 0}), {1, 0, 0});  // Mitsuba: +x is "left" = cross(up, dir)
}

TEST(TransformTest, RejectsSingularAndNonFinite) {
  Transform t;
  Matrix4 m = Matrix4::identity();
  m.m[1][1] = 0;
  EXPECT_FALSE(Transform::from_matrix(m, &t));
  m = Matrix4::identity();
  m.m[0][3] = std::nan("");
  EXPECT_FALSE(Transform::from_matrix(m, &t));
  EXPECT_FALSE(Transform::look_at({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, &t));
}

TEST(TransformTest, NormalsStayPerpendicularUnderNonUniformScale) {
  Transform t = Transform::scale({1, 4, 1});
  Vec3f tangent = t.vector(normalize(Vec3f(1, 1, 0)));
  Vec3f n = t.normal(normalize(Vec3f(1, -1, 0)));
  EXPECT_NEAR(dot(tangent, n), 0.0f, 1e-6f);
}

}  // namespace
}  // namespace gdvr
