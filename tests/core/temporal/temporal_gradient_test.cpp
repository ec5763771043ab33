// Statistical test of the temporal estimators: over independent seeds, the
// mean of dt, dxdt, dydt equals the finite difference of converged PT frames
// (docs/tgpt.md), on the demo scene with a moving box and camera; and the
// frame renderer counts zero temporal rays across static pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <ostream>

#include "core/job/job_runner.h"
#include "core/render/frame_scene.h"
#include "core/scene/mitsuba_loader.h"
#include "core/temporal/temporal_buffers.h"
#include "core/temporal/tgpt_frame.h"
#include "tests/core/temporal/render_buffers.h"
#include "seed_mean_z.h"

namespace gdvr {
namespace {

constexpr int kRes = 16;

// `camera_moves`: the camera also dollies (the path-space shift reconnects
// where the replayed paths decorrelate after the first bounce).
// `matpreview`: instead, the camera of scenes/matpreview moves around the
// smooth-plastic object under its environment map (no shape moves), so the
// path-space shift reconnects at the plastic's diffuse base.
JobSpec moving_job(const std::string& integrator, int spp, uint64_t seed, bool camera_moves = false,
                   const std::string& temporal_shift = "replay", bool matpreview = false) {
  JobSpec job;
  job.temporal_shift = parse_temporal_shift(temporal_shift).value();
  job.scene = matpreview ? "matpreview.xml" : "cbox_demo.xml";
  job.frames = "0,6";  // consecutive frames of the job, a quarter second apart: a clear change
  job.fps = 24;
  job.width = job.height = kRes;
  job.spp = spp;
  job.seed = seed;
  job.integrator = parse_integrator(integrator).value();
  job.reconstruction.method = ReconMethod::kL2;
  if (matpreview) {
    job.params["max_depth"] = "6";  // the scene's -1 (unbounded) only adds deep, dim paths
    Track cam;
    cam.target = "camera";
    Transform t0, t1;
    const Vec3f target(3.04072f, -2.85176f, 2.80939f), up(-0.317366f, 0.312466f, 0.895346f);
    EXPECT_TRUE(Transform::look_at({3.69558f, -3.46243f, 3.25463f}, target, up, &t0));
    EXPECT_TRUE(Transform::look_at({3.89558f, -3.26243f, 3.25463f}, target, up, &t1));
    cam.keys = {Keyframe{0.0, t0}, Keyframe{1.0, t1}};
    job.animation.tracks.push_back(cam);
    return job;
  }
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  job.animation.tracks.push_back(box);
  if (camera_moves) {
    Track cam;
    cam.target = "sensor";
    Transform t0, t1;
    EXPECT_TRUE(Transform::look_at({278, 273, -800}, {278, 273, -799}, {0, 1, 0}, &t0));
    EXPECT_TRUE(Transform::look_at({250, 280, -680}, {275, 265, 0}, {0, 1, 0}, &t1));
    cam.keys = {Keyframe{0.0, t0}, Keyframe{1.0, t1}};
    job.animation.tracks.push_back(cam);
  }
  return job;
}

struct TemporalCase {
  const char* temporal_shift;
  bool camera_moves;
  bool matpreview = false;
};
const char* case_name(const TemporalCase& c) {
  return c.matpreview ? "matpreview_camera_moves" : c.camera_moves ? "camera_moves" : "box_moves";
}
void PrintTo(const TemporalCase& c, std::ostream* os) { *os << c.temporal_shift << "/" << case_name(c); }

std::map<int, FrameBuffers> render(const JobSpec& job) {
  return test::render_buffers(
      job, std::string(GDVR_SOURCE_DIR) + (job.scene == "matpreview.xml" ? "/scenes/matpreview" : "/scenes/demo"), {0, 6});
}

class TemporalGradientTest : public ::testing::TestWithParam<TemporalCase> {};

TEST_P(TemporalGradientTest, MeanEqualsFiniteDifferenceOfConvergedFrames) {
  const TemporalCase tc = GetParam();
  // ---- Converged reference: PT, indirect part (color − direct), 2048 spp ----
  static std::map<std::string, std::map<int, FrameBuffers>> references;
  const std::string key = case_name(tc);
  if (!references.count(key))
    references[key] = render(moving_job("pt", 2048, 77, tc.camera_moves, "replay", tc.matpreview));
  auto& ref = references[key];
  ASSERT_EQ(ref.size(), 2u);
  auto indirect = [&](int f, int x, int y, int c) {
    return double(ref[f].layers.find("")->image.at(x, y, c)) - ref[f].layers.find("direct")->image.at(x, y, c);
  };
  auto ref_var = [&](int f, int x, int y, int c) { return double(ref[f].layers.find("variance")->image.at(x, y, c)); };
  // Reference terms: dt = I1 − I0, dxdt = dx1 − dx0, dydt = dy1 − dy0, with variances.
  const size_t n = size_t(kRes) * kRes * 3;
  std::vector<double> fd(3 * n, 0.0), fd_var(3 * n, 0.0);
  std::vector<bool> defined(3 * n, false);
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t k = (size_t(y) * kRes + x) * 3 + c;
        fd[k] = indirect(6, x, y, c) - indirect(0, x, y, c);
        fd_var[k] = ref_var(6, x, y, c) + ref_var(0, x, y, c);
        defined[k] = true;
        for (int axis = 0; axis < 2; ++axis) {
          const int x1 = x + (axis == 0), y1 = y + (axis == 1);
          if (x1 >= kRes || y1 >= kRes) continue;
          const size_t kk = (axis + 1) * n + k;
          fd[kk] = (indirect(6, x1, y1, c) - indirect(6, x, y, c)) - (indirect(0, x1, y1, c) - indirect(0, x, y, c));
          fd_var[kk] = ref_var(6, x1, y1, c) + ref_var(6, x, y, c) + ref_var(0, x1, y1, c) + ref_var(0, x, y, c);
          defined[kk] = true;
        }
      }

  // ---- T-GPT over independent seeds; motion masks off so every pixel is sampled ----
  // Motion vectors off also turns motion compensation off in stage 2: these
  // are the same-pixel differences, which the finite differences above are.
  // Stage 1 ran with the job's defaults, so pass A of frame 6 replayed pass B
  // along the motion (core/temporal/replay_map.h); its pixels are unbiased
  // either way, which this checks too. The compensated pairs are checked in
  // motion_compensation_test.cpp.
  TgptSettings settings;
  settings.motion_vectors = false;
  constexpr int kSeeds = 12;
  std::vector<double> sum(3 * n, 0.0), sum_sq(3 * n, 0.0);
  double moved = 0;
  for (int s = 0; s < kSeeds; ++s) {
    auto b = render(moving_job("tgpt", 32, 1000 + 7919 * uint64_t(s), tc.camera_moves, tc.temporal_shift,
                               tc.matpreview));
    if (std::string(tc.temporal_shift) == "reconnect") {
      ASSERT_TRUE(b[0].layers.find("dt_fwd") && b[6].layers.find("dt_bwd")) << "no path-space temporal layers";
    }
    ASSERT_EQ(b.size(), 2u);
    auto tg = temporal_gradients(b[0].layers, b[6].layers, settings);
    ASSERT_TRUE(tg.ok()) << tg.status().to_string();
    ASSERT_FALSE(tg->static_pair);
    const Image* terms[3] = {&tg->dt, &tg->dxdt, &tg->dydt};
    for (int t = 0; t < 3; ++t)
      for (size_t k = 0; k < n; ++k) {
        const double v = terms[t]->data()[k];
        ASSERT_TRUE(std::isfinite(v));
        sum[t * n + k] += v;
        sum_sq[t * n + k] += v * v;
      }
  }
  for (size_t k = 0; k < n; ++k) moved += std::abs(fd[k]);
  EXPECT_GT(moved, 1e-3) << "the test needs a visible change between the frames";
  for (int t = 0; t < 3; ++t) {
    test::SeedMeanZ z;
    for (size_t k = t * n; k < (t + 1) * n; ++k)
      if (defined[k]) z.add(sum[k], sum_sq[k], kSeeds, fd[k], fd_var[k]);
    std::printf("[ temporal ] %s/%s/%s: mean z^2 %.3f over %d, aggregate z %.2f, estimator variance %.3g\n",
                tc.temporal_shift, case_name(tc), t == 0 ? "dt" : t == 1 ? "dxdt" : "dydt", z.mean_z2(), z.count,
                z.aggregate_z(), z.sum_seed_var / std::max(1, z.count));
    // Student t with 11 dof: E[z^2] = 11/9; a biased estimator shows as a clear excess.
    EXPECT_LT(z.mean_z2(), 1.8);
    EXPECT_LT(std::abs(z.aggregate_z()), 4.5);
  }
}

INSTANTIATE_TEST_SUITE_P(Shifts, TemporalGradientTest,
                         ::testing::Values(TemporalCase{"replay", false}, TemporalCase{"reconnect", false},
                                           TemporalCase{"replay", true}, TemporalCase{"reconnect", true},
                                           TemporalCase{"reconnect", true, true}),
                         [](const auto& info) {
                           return std::string(info.param.temporal_shift) + "_" + case_name(info.param);
                         });

// The frame renderer's ray accounting: zero temporal rays across static pairs.
TEST(TemporalRayTest, StaticNeighboursTraceNoTemporalRays) {
  LoadOptions load;
  load.params = {{"res", std::to_string(kRes)}};
  auto desc = load_mitsuba_scene(std::string(GDVR_SOURCE_DIR) + "/scenes/demo/cbox_demo.xml", load);
  ASSERT_TRUE(desc.ok());
  auto fs = FrameScene::create(desc.value(), {});
  ASSERT_TRUE(fs.ok());
  FrameRenderSettings rs;
  rs.width = rs.height = kRes;
  rs.spp = 2;
  rs.threads = 2;
  TgptSettings settings;
  TgptNeighbourhood nb;
  nb.at_t = nb.prev = nb.next = &desc.value();
  auto r = render_tgpt_frame(*fs.value(), rs, settings, {1, 2}, nb, nullptr, {});
  ASSERT_TRUE(r.ok()) << r.status().to_string();
  EXPECT_EQ(r->temporal_rays, 0u);
  EXPECT_GT(r->rays, 0u);
  EXPECT_TRUE(r->forward.offsets.empty());
  EXPECT_TRUE(r->backward.offsets.empty());

  // Moving camera towards the next frame: motion rays are temporal rays.
  Scene next = desc.value();
  next.camera.to_world = Transform::translate({5, 0, 0}) * next.camera.to_world;
  nb.next = &next;
  nb.to_next = detect_changes(desc.value(), next);
  auto m = render_tgpt_frame(*fs.value(), rs, settings, {1, 2}, nb, nullptr, {});
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->temporal_rays, uint64_t(kRes * kRes));
  EXPECT_FALSE(m->forward.offsets.empty());
}

}  // namespace
}  // namespace gdvr
