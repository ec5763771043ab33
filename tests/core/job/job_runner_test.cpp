// The job runner end to end on the bundled demo animation, at tiny sizes.
#include "core/job/job_runner.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr {
namespace {

std::string demo_dir() { return std::string(GDVR_SOURCE_DIR) + "/scenes/demo"; }

JobSpec small_demo_job(const std::string& frames) {
  JobSpec job;
  job.scene = "cbox_demo.xml";
  job.frames = frames;
  job.fps = 24;
  job.width = job.height = 24;
  job.spp = 2;
  job.seed = 3;
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  job.animation.tracks.push_back(box);
  return job;
}

TEST(JobRunnerTest, FramesArriveInOrderWithLayersAndProgress) {
  JobSpec job = small_demo_job("0-3");
  JobRunOptions options;
  options.base_dir = demo_dir();
  std::vector<int> frames;
  double last_fraction = -1;
  bool monotonic = true;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& out) {
    frames.push_back(out.frame);
    ASSERT_NE(out.image.find(""), nullptr);
    ASSERT_NE(out.image.find("direct"), nullptr);
    ASSERT_NE(out.image.find("variance"), nullptr);
    for (float v : out.image.find("")->image.data()) ASSERT_TRUE(std::isfinite(v));
    EXPECT_GT(out.stats.rays, 0u);
    EXPECT_EQ(out.stats.spp, 2);
  };
  cb.on_progress = [&](const JobProgress& p) {
    if (p.fraction + 1e-9 < last_fraction) monotonic = false;
    last_fraction = p.fraction;
  };
  Status st = run_job(job, options, cb, nullptr);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(frames, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_TRUE(monotonic);
  EXPECT_NEAR(last_fraction, 1.0, 1e-9);
}

// Moving a shape through an Embree instance must give the image of a static
// scene in which the same transform is baked into the shape.
TEST(JobRunnerTest, AnimatedInstanceMatchesBakedTransform) {
  JobSpec job = small_demo_job("24");
  JobRunOptions options;
  options.base_dir = demo_dir();
  Image animated;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& out) { animated = out.image.find("")->image; };
  ASSERT_TRUE(run_job(job, options, cb, nullptr).ok());

  auto scene = load_mitsuba_scene(demo_dir() + "/cbox_demo.xml", {});
  ASSERT_TRUE(scene.ok()) << scene.status().to_string();
  for (Shape& s : scene->shapes)
    if (s.id == "smallbox") s.to_world = evaluate_track(job.animation.tracks[0], 24 / 24.0);
  auto fs = FrameScene::create(scene.value(), {});  // nothing instanced: baked into world space
  ASSERT_TRUE(fs.ok());
  FrameRenderSettings settings;
  settings.width = settings.height = 24;
  settings.spp = 2;
  settings.seed = 3;
  settings.path.max_depth = scene->defaults.max_depth;
  auto baked = render_frame_pt(*fs.value(), settings, 24, {});
  ASSERT_TRUE(baked.ok());
  ASSERT_EQ(animated.data().size(), baked->color.data().size());
  double diff = 0, total = 0;
  for (size_t i = 0; i < animated.data().size(); ++i) {
    diff += std::abs(animated.data()[i] - baked->color.data()[i]);
    total += std::abs(baked->color.data()[i]);
  }
  // Identical sample streams; only float rounding of instanced vs baked
  // intersections may differ (which can flip a rare path).
  EXPECT_LT(diff / total, 0.02);
  // And the box really moved: frame 0 differs.
  JobSpec first = small_demo_job("0");
  Image frame0;
  cb.on_frame_final = [&](const FrameOutput& out) { frame0 = out.image.find("")->image; };
  ASSERT_TRUE(run_job(first, options, cb, nullptr).ok());
  double moved = 0;
  for (size_t i = 0; i < frame0.data().size(); ++i) moved += std::abs(frame0.data()[i] - animated.data()[i]);
  EXPECT_GT(moved / total, 0.05);
}

// What the loader replaced (here the scene's tent filter: gdvr renders box
// pixels) reaches every frame's left_out, without the server's directories.
TEST(JobRunnerTest, SceneApproximationsAreReportedWithEveryFrame) {
  JobSpec job;
  job.scene = "scene.xml";
  job.frames = "0-1";
  job.width = 16;
  job.height = 9;
  job.spp = 1;
  JobRunOptions options;
  options.base_dir = std::string(GDVR_SOURCE_DIR) + "/scenes/veach-mis";
  std::vector<std::vector<std::string>> left_out;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& out) { left_out.push_back(out.stats.left_out); };
  ASSERT_TRUE(run_job(job, options, cb, nullptr).ok());
  ASSERT_EQ(left_out.size(), 2u);
  for (const auto& notes : left_out) {
    bool filter = false;
    for (const std::string& n : notes) {
      filter = filter || n.find("rfilter 'tent' replaced by box") != std::string::npos;
      EXPECT_EQ(n.find(GDVR_SOURCE_DIR), std::string::npos) << n;
    }
    EXPECT_TRUE(filter) << "no note of the replaced pixel filter";
  }
}

TEST(JobRunnerTest, SkippedFramesAreNotRenderedAgain) {
  JobSpec job = small_demo_job("0-3");
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.skip_frames = {0, 2};
  std::vector<int> frames;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& out) { frames.push_back(out.frame); };
  ASSERT_TRUE(run_job(job, options, cb, nullptr).ok());
  EXPECT_EQ(frames, (std::vector<int>{1, 3}));
}

TEST(JobRunnerTest, CancelStopsTheJob) {
  JobSpec job = small_demo_job("0-100");
  JobRunOptions options;
  options.base_dir = demo_dir();
  std::atomic<bool> cancel{false};
  int frames = 0;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput&) {
    if (++frames == 2) cancel = true;
  };
  Status st = run_job(job, options, cb, &cancel);
  EXPECT_EQ(st.code(), StatusCode::kCancelled);
  EXPECT_EQ(frames, 2);
}

TEST(JobRunnerTest, BadJobsAreRejectedWithTheFieldNamed) {
  JobRunOptions options;
  options.base_dir = demo_dir();
  JobSpec job = small_demo_job("0");
  job.scene = "missing.xml";
  Status st = validate_job(job, options);
  EXPECT_EQ(st.code(), StatusCode::kNotFound);
  EXPECT_NE(st.message().find("job.scene"), std::string::npos);
  job = small_demo_job("5-1");
  st = validate_job(job, options);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("job.frames"), std::string::npos);
  job = small_demo_job("0");
  job.width = 100000;
  EXPECT_EQ(validate_job(job, options).code(), StatusCode::kInvalidArgument);
  job = small_demo_job("0");
  job.animation.tracks[0].target = "no_such_shape";
  EXPECT_FALSE(validate_job(job, options).ok());
  job = small_demo_job("0");
  options.asset_root = demo_dir();
  job.scene = "../cbox/cbox-rgb.xml";
  st = validate_job(job, options);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("asset root"), std::string::npos);
}

}  // namespace
}  // namespace gdvr
