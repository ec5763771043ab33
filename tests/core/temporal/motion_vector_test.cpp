// Motion vectors by primary-hit reprojection and the forward/backward check.
#include "core/temporal/motion_vectors.h"

#include <gtest/gtest.h>

#include "core/render/frame_scene.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr {
namespace {

constexpr int kRes = 24;

Scene demo_scene() {
  LoadOptions load;
  load.params = {{"res", std::to_string(kRes)}};
  auto desc = load_mitsuba_scene(std::string(GDVR_SOURCE_DIR) + "/scenes/demo/cbox_demo.xml", load);
  EXPECT_TRUE(desc.ok()) << desc.status().to_string();
  return desc.ok() ? std::move(desc.value()) : Scene{};
}

TEST(MotionVectorTest, StaticSceneHasZeroMotionEverywhere) {
  Scene desc = demo_scene();
  auto fs = FrameScene::create(desc, {});
  ASSERT_TRUE(fs.ok());
  MotionField m = compute_motion_field(*fs.value(), desc, desc, kRes, kRes, 2);
  EXPECT_EQ(m.rays, uint64_t(kRes * kRes));
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) {
      EXPECT_EQ(m.offsets.at(x, y, 0), 0.0f);
      EXPECT_EQ(m.offsets.at(x, y, 1), 0.0f);
      EXPECT_EQ(m.offsets.at(x, y, 2), 1.0f);
    }
  TemporalMask mask = temporal_consistency(m.offsets, m.offsets, TgptSettings{});
  EXPECT_EQ(mask.failed, 0);
}

// A camera panning sideways shifts every pixel the same way (for a far wall),
// and the forward/backward round trip passes except where content leaves the image.
TEST(MotionVectorTest, CameraPanShiftsPixelsAndPassesTheRoundTrip) {
  Scene t0 = demo_scene(), t1 = t0;
  // Rotate the camera about its own y axis by ~one pixel's angle per frame.
  const float pixel_deg = 39.3077f / kRes;
  t1.camera.to_world = t0.camera.to_world * Transform::rotate({0, 1, 0}, 3.0f * pixel_deg);
  auto f0 = FrameScene::create(t0, {});
  auto f1 = FrameScene::create(t1, {});
  ASSERT_TRUE(f0.ok() && f1.ok());
  MotionField fwd = compute_motion_field(*f0.value(), t0, t1, kRes, kRes, 2);
  MotionField bwd = compute_motion_field(*f1.value(), t1, t0, kRes, kRes, 2);
  // Central pixel: moves by ~3 px horizontally, not vertically (the field
  // keeps fractions; motion_pixel_offset rounds them).
  const int c = kRes / 2;
  EXPECT_EQ(std::abs(motion_pixel_offset(fwd.offsets.at(c, c, 0))), 3);
  EXPECT_NEAR(std::abs(fwd.offsets.at(c, c, 0)), 3.0f, 0.25f);
  EXPECT_EQ(motion_pixel_offset(fwd.offsets.at(c, c, 1)), 0);
  EXPECT_EQ(motion_pixel_offset(fwd.offsets.at(c, c, 0)), -motion_pixel_offset(bwd.offsets.at(c, c, 0)));
  TgptSettings s;
  s.max_same_pixel_motion_px = -1;  // round trip only
  TemporalMask mask = temporal_consistency(fwd.offsets, bwd.offsets, s);
  // Only the three columns leaving (or entering) the image may fail.
  EXPECT_LE(mask.failed, int64_t(2 * 3 * kRes));
  EXPECT_TRUE(mask.valid[size_t(c) * kRes + c]);
  // With the same-pixel limit of 1 px a 3 px motion drops the constraint.
  TgptSettings strict;
  TemporalMask strict_mask = temporal_consistency(fwd.offsets, bwd.offsets, strict);
  EXPECT_FALSE(strict_mask.valid[size_t(c) * kRes + c]);
}

// The fields keep the fractional film offset: a pan by a fraction of a pixel's
// angle moves every pixel by that fraction, not by a whole pixel or none.
TEST(MotionVectorTest, FieldsKeepFractionalOffsets) {
  Scene t0 = demo_scene(), t1 = t0;
  const float pixel_deg = 39.3077f / kRes;
  t1.camera.to_world = t0.camera.to_world * Transform::rotate({0, 1, 0}, 0.4f * pixel_deg);
  auto f0 = FrameScene::create(t0, {});
  ASSERT_TRUE(f0.ok());
  MotionField fwd = compute_motion_field(*f0.value(), t0, t1, kRes, kRes, 2);
  double sum = 0;
  int count = 0;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) {
      if (fwd.offsets.at(x, y, 2) == 0.0f) continue;
      const float m = std::abs(fwd.offsets.at(x, y, 0));
      EXPECT_GT(m, 0.3f) << x << "," << y;
      EXPECT_LT(m, 0.5f) << x << "," << y;
      EXPECT_EQ(motion_pixel_offset(fwd.offsets.at(x, y, 0)), 0);
      sum += m;
      ++count;
    }
  ASSERT_GT(count, kRes * kRes / 2);
  EXPECT_NEAR(sum / count, 0.4, 0.05);
  // The same-pixel check rounds with the same rule: a 0.4 px motion is no motion.
  MotionField bwd = fwd;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) bwd.offsets.at(x, y, 0) = -fwd.offsets.at(x, y, 0);
  TgptSettings strict;
  strict.max_same_pixel_motion_px = 0;
  EXPECT_EQ(temporal_consistency(fwd.offsets, bwd.offsets, strict).failed, int64_t(kRes * kRes) - count);
}

// One rounding rule: the pixel whose footprint [x, x+1) holds the landing point
// x + 0.5 + m (ties go right/down).
TEST(MotionVectorTest, PixelOffsetRoundsToTheFootprintOfTheLandingPoint) {
  EXPECT_EQ(motion_pixel_offset(0.0f), 0);
  EXPECT_EQ(motion_pixel_offset(0.49f), 0);
  EXPECT_EQ(motion_pixel_offset(0.5f), 1);
  EXPECT_EQ(motion_pixel_offset(-0.5f), 0);
  EXPECT_EQ(motion_pixel_offset(-0.51f), -1);
  EXPECT_EQ(motion_pixel_offset(1.2f), 1);
  EXPECT_EQ(motion_pixel_offset(-1.7f), -2);
  EXPECT_EQ(motion_pixel_offset(-2.5f), -2);
  EXPECT_EQ(motion_pixel_offset(3.0f), 3);
  for (float m = -3.0f; m <= 3.0f; m += 0.0625f) {
    const int o = motion_pixel_offset(m);
    EXPECT_LE(float(o), 0.5f + m) << m;
    EXPECT_GT(float(o + 1), 0.5f + m) << m;
  }
}

// The moving box occludes floor pixels it moves onto: those fail the check.
TEST(MotionVectorTest, OcclusionFailsTheCheck) {
  Scene t0 = demo_scene(), t1 = t0;
  int box = -1;
  for (size_t i = 0; i < t0.shapes.size(); ++i)
    if (t0.shapes[i].id == "smallbox") box = int(i);
  ASSERT_GE(box, 0);
  t1.shapes[size_t(box)].to_world = Transform::translate({-120, 0, 0}) * t0.shapes[size_t(box)].to_world;
  std::vector<bool> animated(t0.shapes.size(), false);
  animated[size_t(box)] = true;
  auto f0 = FrameScene::create(t0, animated);
  auto f1 = FrameScene::create(t1, animated);
  ASSERT_TRUE(f0.ok() && f1.ok());
  MotionField fwd = compute_motion_field(*f0.value(), t0, t1, kRes, kRes, 2);
  MotionField bwd = compute_motion_field(*f1.value(), t1, t0, kRes, kRes, 2);
  TgptSettings s;
  s.max_same_pixel_motion_px = -1;
  TemporalMask mask = temporal_consistency(fwd.offsets, bwd.offsets, s);
  int moving = 0;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) moving += fwd.offsets.at(x, y, 0) != 0.0f;
  EXPECT_GT(moving, 0);
  EXPECT_GT(mask.failed, 0);                      // occluded floor pixels
  EXPECT_LT(mask.failed, int64_t(kRes * kRes / 2));  // the walls are untouched
}

}  // namespace
}  // namespace gdvr
