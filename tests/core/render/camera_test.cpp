#include <gtest/gtest.h>

#include "core/math/rng.h"
#include "core/render/perspective_camera.h"

namespace gdvr {
namespace {

TEST(CameraTest, FovAxisConversions) {
  Camera c;
  c.fov = 40;
  c.fov_axis = FovAxis::kX;
  EXPECT_NEAR(fov_x_degrees(c, 200, 100), 40.0f, 1e-4f);
  c.fov_axis = FovAxis::kY;  // tan(x/2) = aspect * tan(y/2)
  EXPECT_NEAR(std::tan(radians(fov_x_degrees(c, 200, 100)) / 2), 2 * std::tan(radians(20.0f)), 1e-5f);
  c.fov_axis = FovAxis::kSmaller;  // landscape: smaller is y
  EXPECT_NEAR(fov_x_degrees(c, 200, 100), ([&] { Camera d = c; d.fov_axis = FovAxis::kY; return fov_x_degrees(d, 200, 100); })(), 1e-5f);
  c.fov_axis = FovAxis::kLarger;
  EXPECT_NEAR(fov_x_degrees(c, 200, 100), 40.0f, 1e-4f);
  c.fov_axis = FovAxis::kDiagonal;  // diagonal tan = sqrt(tx^2 + ty^2)
  float tx = std::tan(radians(fov_x_degrees(c, 200, 100)) / 2);
  EXPECT_NEAR(std::sqrt(tx * tx + tx * tx / 4), std::tan(radians(20.0f)), 1e-5f);
}

TEST(CameraTest, ProjectInvertsGenerateRay) {
  Camera c;
  ASSERT_TRUE(Transform::look_at({1, 2, 3}, {0, 0, 0}, {0, 1, 0}, &c.to_world));
  c.fov = 50;
  PerspectiveCamera cam(c, 64, 48);
  for (Vec2f film : {Vec2f(0.5f, 0.5f), Vec2f(32, 24), Vec2f(60.25f, 3.75f)}) {
    Ray r = cam.generate_ray(film);
    Vec2f back;
    ASSERT_TRUE(cam.project(r.o + r.d * 7.0f, &back));
    EXPECT_NEAR(back.x, film.x, 1e-3f);
    EXPECT_NEAR(back.y, film.y, 1e-3f);
  }
}

// The film rectangle of a box contains the image of every point of the box
// (projected even outside the image), and a box that reaches to or behind the
// near plane has no bounded image.
TEST(CameraTest, ProjectBoundsContainsTheImageOfTheWholeBox) {
  Camera c;
  ASSERT_TRUE(Transform::look_at({1, 2, 3}, {0, 0, 0}, {0, 1, 0}, &c.to_world));
  c.fov = 50;
  PerspectiveCamera cam(c, 64, 48);
  Bounds3f box;
  box.expand({-0.5f, -0.2f, -0.3f});
  box.expand({0.4f, 0.6f, 0.2f});
  Vec2f lo, hi;
  ASSERT_TRUE(cam.project_bounds(box, &lo, &hi));
  EXPECT_LT(lo.x, hi.x);
  EXPECT_LT(lo.y, hi.y);
  Sampler sampler(3, 0, 0, 0, 0);
  int inside_image = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3f p(box.lo.x + (box.hi.x - box.lo.x) * sampler.next_1d(),
                  box.lo.y + (box.hi.y - box.lo.y) * sampler.next_1d(),
                  box.lo.z + (box.hi.z - box.lo.z) * sampler.next_1d());
    // Where the camera ray through p meets the film (project() also reports
    // points beyond the image's border there).
    Vec2f film;
    inside_image += cam.project(p, &film);
    EXPECT_GE(film.x, lo.x - 1e-3f);
    EXPECT_LE(film.x, hi.x + 1e-3f);
    EXPECT_GE(film.y, lo.y - 1e-3f);
    EXPECT_LE(film.y, hi.y + 1e-3f);
  }
  EXPECT_GT(inside_image, 0);
  Bounds3f around_camera = box;
  around_camera.expand({1, 2, 3});
  EXPECT_FALSE(cam.project_bounds(around_camera, &lo, &hi));
  EXPECT_FALSE(cam.project_bounds(Bounds3f(), &lo, &hi)) << "empty box";
}

// Mitsuba's convention: image right is the camera's -x (cross(dir, up)).
TEST(CameraTest, ImageRightIsCrossOfViewAndUp) {
  Camera c;
  ASSERT_TRUE(Transform::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, &c.to_world));
  c.fov = 90;
  PerspectiveCamera cam(c, 10, 10);
  Ray right = cam.generate_ray({9.9f, 5.0f});
  Ray top = cam.generate_ray({5.0f, 0.1f});
  EXPECT_LT(right.d.x, -0.5f);  // cross(+z, +y) = -x
  EXPECT_GT(top.d.y, 0.5f);
}

}  // namespace
}  // namespace gdvr
