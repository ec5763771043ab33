// What changes between two frames: nothing for a static scene, exactly the
// animated shape / the camera otherwise.
#include "core/temporal/change_detection.h"

#include <gtest/gtest.h>

#include "core/scene/animation.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr {
namespace {

Scene demo_scene() {
  LoadOptions load;
  load.params = {{"res", "16"}};
  auto desc = load_mitsuba_scene(std::string(GDVR_SOURCE_DIR) + "/scenes/demo/cbox_demo.xml", load);
  EXPECT_TRUE(desc.ok()) << desc.status().to_string();
  return desc.ok() ? std::move(desc.value()) : Scene{};
}

TEST(ChangeDetectionTest, StaticPairChangesNothing) {
  Scene a = demo_scene(), b = a;
  FramePairChanges c = detect_changes(a, b);
  EXPECT_FALSE(c.any());
  EXPECT_EQ(c.describe(), "nothing");
}

TEST(ChangeDetectionTest, FindsTheMovingShapeAndTheCamera) {
  Scene a = demo_scene();
  Animation anim;
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  anim.tracks.push_back(box);
  Scene t0 = a, t1 = a;
  ASSERT_TRUE(apply_animation(anim, 0.0, &t0).ok());
  ASSERT_TRUE(apply_animation(anim, 0.5, &t1).ok());
  FramePairChanges c = detect_changes(t0, t1);
  EXPECT_FALSE(c.camera);
  ASSERT_EQ(c.shapes.size(), 1u);
  EXPECT_EQ(c.shapes[0], "smallbox");
  EXPECT_TRUE(c.emitters.empty());
  EXPECT_TRUE(c.materials.empty());

  // A track past its last key holds: no change.
  Scene t2 = a, t3 = a;
  ASSERT_TRUE(apply_animation(anim, 2.0, &t2).ok());
  ASSERT_TRUE(apply_animation(anim, 3.0, &t3).ok());
  EXPECT_FALSE(detect_changes(t2, t3).any());

  Scene moved = a;
  moved.camera.to_world = Transform::translate({1, 0, 0}) * moved.camera.to_world;
  FramePairChanges cc = detect_changes(a, moved);
  EXPECT_TRUE(cc.camera);
  EXPECT_TRUE(cc.shapes.empty());
  EXPECT_EQ(cc.describe(), "camera");
}

}  // namespace
}  // namespace gdvr
