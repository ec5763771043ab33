#include "core/scene/animation.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gdvr {
namespace {

Keyframe key(double time, const Transform& t) {
  Keyframe k;
  k.time = time;
  k.to_world = t;
  return k;
}

Track make_track(Interpolation interp, std::vector<Keyframe> keys) {
  Track t;
  t.target = "sensor";
  t.interpolation = interp;
  t.keys = std::move(keys);
  return t;
}

void expect_near(Vec3f a, Vec3f b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(AnimationTest, ExactAtKeysAndClampedOutside) {
  Transform a = Transform::translate(Vec3f(1, 2, 3)) * Transform::rotate(Vec3f(1, 1, 0), 30.0f);
  Matrix4 shear = Matrix4::identity();
  shear.m[0][1] = 0.5;  // sheared key: still returned exactly at its time
  Transform b;
  ASSERT_TRUE(Transform::from_matrix(shear, &b));
  for (Interpolation i : {Interpolation::kStep, Interpolation::kLinear, Interpolation::kCubic}) {
    Track t = make_track(i, {key(0, a), key(1, b), key(2, a)});
    EXPECT_EQ(evaluate_track(t, 0.0), a);
    EXPECT_EQ(evaluate_track(t, 1.0), b);
    EXPECT_EQ(evaluate_track(t, 2.0), a);
    EXPECT_EQ(evaluate_track(t, -5.0), a);
    EXPECT_EQ(evaluate_track(t, 7.0), a);
  }
}

TEST(AnimationTest, LinearTranslationMidpoint) {
  Track t = make_track(Interpolation::kLinear,
                       {key(0, Transform::translate(Vec3f(0, 0, 0))), key(2, Transform::translate(Vec3f(4, -2, 6)))});
  expect_near(evaluate_track(t, 1.0).point(Vec3f(0.0f)), Vec3f(2, -1, 3));
  expect_near(evaluate_track(t, 0.5).point(Vec3f(0.0f)), Vec3f(1, -0.5f, 1.5f));
}

TEST(AnimationTest, SlerpOf90DegreesGives45) {
  Track t = make_track(Interpolation::kLinear,
                       {key(0, Transform()), key(1, Transform::rotate(Vec3f(0, 0, 1), 90.0f))});
  Vec3f x = evaluate_track(t, 0.5).vector(Vec3f(1, 0, 0));
  float angle = std::atan2(x.y, x.x) * 180.0f / kPi;
  EXPECT_NEAR(angle, 45.0f, 1e-4f);
  EXPECT_NEAR(length(x), 1.0f, 1e-6f);
}

TEST(AnimationTest, StepHoldsPreviousKey) {
  Transform a = Transform::translate(Vec3f(1, 0, 0)), b = Transform::translate(Vec3f(5, 0, 0));
  Track t = make_track(Interpolation::kStep, {key(0, a), key(1, b)});
  EXPECT_EQ(evaluate_track(t, 0.99), a);
  EXPECT_EQ(evaluate_track(t, 1.0), b);
}

TEST(AnimationTest, ScaleInterpolatesAndMirrorsSurvive) {
  Track t = make_track(Interpolation::kLinear,
                       {key(0, Transform::scale(Vec3f(1, 1, 1))), key(1, Transform::scale(Vec3f(3, 1, 1)))});
  expect_near(evaluate_track(t, 0.5).vector(Vec3f(1, 0, 0)), Vec3f(2, 0, 0));
  Track m = make_track(Interpolation::kLinear,
                       {key(0, Transform::scale(Vec3f(-1, 1, 1))), key(1, Transform::scale(Vec3f(-3, 1, 1)))});
  expect_near(evaluate_track(m, 0.5).vector(Vec3f(1, 0, 0)), Vec3f(-2, 0, 0));
  expect_near(evaluate_track(m, 0.5).vector(Vec3f(0, 1, 0)), Vec3f(0, 1, 0));
}

TEST(AnimationTest, CubicPassesThroughKeysAndIsSmoothOnALine) {
  // Keys on a straight line with uniform spacing: Catmull-Rom reproduces it.
  std::vector<Keyframe> keys;
  for (int i = 0; i < 4; ++i) keys.push_back(key(i, Transform::translate(Vec3f(float(2 * i), 0, 0))));
  Track t = make_track(Interpolation::kCubic, keys);
  expect_near(evaluate_track(t, 1.5).point(Vec3f(0.0f)), Vec3f(3, 0, 0));
  expect_near(evaluate_track(t, 1.25).point(Vec3f(0.0f)), Vec3f(2.5f, 0, 0));
}

TEST(AnimationTest, ValidateAndApply) {
  Scene scene;
  scene.source = "test";
  Shape s;
  s.id = "box";
  scene.shapes.push_back(s);
  Emitter e;
  e.type = EmitterType::kPoint;
  e.id = "lamp";
  scene.emitters.push_back(e);
  Animation anim;
  anim.tracks.push_back(make_track(Interpolation::kLinear, {key(0, Transform()), key(1, Transform::translate(Vec3f(0, 2, 0)))}));
  Track box = make_track(Interpolation::kLinear, {key(0, Transform()), key(1, Transform::translate(Vec3f(4, 0, 0)))});
  box.target = "box";
  anim.tracks.push_back(box);
  Track lamp = box;
  lamp.target = "lamp";
  anim.tracks.push_back(lamp);
  ASSERT_TRUE(validate_animation(anim, scene).ok());
  ASSERT_TRUE(apply_animation(anim, 0.5, &scene).ok());
  expect_near(scene.camera.to_world.point(Vec3f(0.0f)), Vec3f(0, 1, 0));
  expect_near(scene.shapes[0].to_world.point(Vec3f(0.0f)), Vec3f(2, 0, 0));
  expect_near(scene.emitters[0].to_world.point(Vec3f(0.0f)), Vec3f(2, 0, 0));

  Animation bad = anim;
  bad.tracks[1].target = "nothing";
  EXPECT_EQ(validate_animation(bad, scene).code(), StatusCode::kInvalidArgument);  // a bad job, not a missing file
  bad = anim;
  bad.tracks[0].keys[1].time = 0;
  EXPECT_EQ(validate_animation(bad, scene).code(), StatusCode::kInvalidArgument);
  bad = anim;
  bad.tracks[0].keys.clear();
  EXPECT_EQ(validate_animation(bad, scene).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace gdvr
