// T-GPT end to end through the job runner on the demo scene at tiny sizes:
// static shots, W = 1, short shots, streaming order, stage equality, layers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/image/error_metrics.h"
#include "core/job/job_runner.h"
#include "core/recon/reconstruct.h"
#include "core/temporal/temporal_buffers.h"
#include "core/temporal/tgpt_frame.h"

namespace gdvr {
namespace {

std::string demo_dir() { return std::string(GDVR_SOURCE_DIR) + "/scenes/demo"; }

JobSpec tgpt_job(const std::string& temporal_shift, const std::string& frames, bool animated, int window) {
  JobSpec job;
  job.temporal_shift = parse_temporal_shift(temporal_shift).value();
  job.scene = "cbox_demo.xml";
  job.frames = frames;
  job.fps = 24;
  job.width = job.height = 16;
  job.spp = 4;
  job.seed = 5;
  job.integrator = Integrator::kTgpt;
  job.reconstruction.method = ReconMethod::kL2;
  job.reconstruction.window = window;
  if (animated) {
    Track box;
    box.target = "smallbox";
    box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
    job.animation.tracks.push_back(box);
    Track cam;
    cam.target = "sensor";
    Transform a, b;
    EXPECT_TRUE(Transform::look_at({278, 273, -800}, {278, 273, -799}, {0, 1, 0}, &a));
    EXPECT_TRUE(Transform::look_at({250, 280, -680}, {275, 265, 0}, {0, 1, 0}, &b));
    cam.keys = {Keyframe{0.0, a}, Keyframe{2.0, b}};
    job.animation.tracks.push_back(cam);
  }
  return job;
}

// memory_limit_bytes >= 0: run_job spills its buffered frames beyond it.
std::vector<FrameOutput> run(const JobSpec& job, long long memory_limit_bytes = -1) {
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.threads = 2;
  options.memory_limit_bytes = memory_limit_bytes;
  options.spill_dir = ::testing::TempDir();
  std::vector<FrameOutput> out;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& f) { out.push_back(f); };
  Status st = run_job(job, options, cb, nullptr);
  EXPECT_TRUE(st.ok()) << st.to_string();
  return out;
}

bool has(const std::vector<std::string>& v, const std::string& prefix) {
  for (const auto& s : v)
    if (s.rfind(prefix, 0) == 0) return true;
  return false;
}

void expect_finite_layers(const FrameOutput& f) {
  for (const ImageLayer& l : f.image.layers)
    for (float v : l.image.data()) ASSERT_TRUE(std::isfinite(v)) << "frame " << f.frame << " layer " << l.name;
}

// Every test runs with both temporal shifts (replay, reconnect).
class TgptJobTest : public ::testing::TestWithParam<std::string> {};

TEST_P(TgptJobTest, StaticShotHasExactlyZeroTemporalGradients) {
  auto out = run(tgpt_job(GetParam(), "0-3", /* animated = */ false, /* window = */ 4));
  ASSERT_EQ(out.size(), 4u);
  for (const FrameOutput& f : out) {
    expect_finite_layers(f);
    for (const char* name : {"dt", "dxdt", "dydt", "temporal_failure_rate"}) {
      const ImageLayer* l = f.image.find(name);
      ASSERT_NE(l, nullptr) << name;
      for (float v : l->image.data()) ASSERT_EQ(v, 0.0f) << name << " frame " << f.frame;
    }
    EXPECT_TRUE(has(f.stats.left_out, f.frame == 3 ? "temporal offsets: last frame" : "temporal offsets and motion vectors: static frame pair"))
        << f.frame;
    // Pass A of frames 1..3 is the previous pass B, copied, not rendered.
    EXPECT_EQ(has(f.stats.left_out, "pass A: equals the previous frame's pass B"), f.frame > 0);
    EXPECT_EQ(f.stats.temporal_rays, 0u) << "a static shot traces no temporal ray";
    // The path-space shift's dt is same-pixel: the frame says so.
    EXPECT_EQ(has(f.stats.left_out, "motion compensation: not with temporal_shift reconnect"), GetParam() == "reconnect");
  }
}

// A fully static pair traces no temporal rays; a moving one does.
TEST_P(TgptJobTest, StaticPairTracesZeroTemporalRays) {
  JobSpec job = tgpt_job(GetParam(), "0-1", false, 2);
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.threads = 2;
  // Two separate stage-1 runs (as two farm processes): frame 1's pass A is
  // rendered, not copied from frame 0's pass B.
  std::map<int, FrameBuffers> buffers;
  for (int f : {0, 1})
    ASSERT_TRUE(render_job_buffers(job, options, {f}, [&](FrameBuffers&& b) {
                  buffers[b.frame] = std::move(b);
                  return Status::Ok();
                }, nullptr, nullptr).ok());
  EXPECT_FALSE(has(buffers[1].stats.left_out, "pass A: equals"));
  // No motion layers: stage 2 reads the pair as static and forms dt ≡ 0 without subtracting.
  EXPECT_EQ(buffers[0].layers.find("motion"), nullptr);
  EXPECT_EQ(buffers[1].layers.find("motion_back"), nullptr);
  auto tg = temporal_gradients(buffers[0].layers, buffers[1].layers, TgptSettings{});
  ASSERT_TRUE(tg.ok());
  EXPECT_TRUE(tg->static_pair);
  // In a static pair B_0 and A_1 are the same estimate (same scene, same numbers).
  EXPECT_EQ(buffers[0].layers.find("b_primal")->image.data(), buffers[1].layers.find("a_primal")->image.data());
}

TEST_P(TgptJobTest, StaticShotEqualsReconstructingWithZeroDt) {
  JobSpec job = tgpt_job(GetParam(), "0-2", false, 3);
  auto out = run(job);
  ASSERT_EQ(out.size(), 3u);
  GradientWindow window;
  for (const FrameOutput& f : out) {
    GradientFrame gf;
    for (auto [t, n] : {std::pair<Term, const char*>{Term::kPrimal, "primal"}, {Term::kDx, "dx"}, {Term::kDy, "dy"}}) {
      gf.buffer(t) = f.image.find(n)->image;
      gf.variance(t) = f.image.find(std::string(n) + "_var")->image;
    }
    for (Term t : {Term::kDt, Term::kDxdt, Term::kDydt}) {
      gf.buffer(t) = Image(16, 16, 3);  // dt = 0
      gf.variance(t) = Image(16, 16, 3);
    }
    window.frames.push_back(std::make_shared<const GradientFrame>(std::move(gf)));
  }
  ReconSettings rs;
  rs.method = ReconMethod::kL2;
  rs.alpha = job.reconstruction.alpha;
  auto solved = reconstruct(window, rs);
  ASSERT_TRUE(solved.ok());
  for (size_t i = 0; i < out.size(); ++i) {
    const Image& fin = out[i].image.find("")->image;
    const Image& direct = out[i].image.find("direct")->image;
    // Equal up to the Hann blend's normalisation w·x·(1/w) (one rounding);
    // the final image is clamped at 0 (finalize_frame).
    for (size_t k = 0; k < fin.data().size(); ++k)
      ASSERT_NEAR(fin.data()[k], std::max(solved->frames[i].data()[k] + direct.data()[k], 0.0f),
                  1e-6f * (1.0f + std::abs(fin.data()[k]))) << "frame " << i;
  }
}

TEST_P(TgptJobTest, WindowOfOneIsSpatialGpt) {
  JobSpec job = tgpt_job(GetParam(), "0-2", true, 1);
  auto out = run(job);
  ASSERT_EQ(out.size(), 3u);
  for (const FrameOutput& f : out) {
    expect_finite_layers(f);
    GradientFrame gf;
    for (auto [t, n] : {std::pair<Term, const char*>{Term::kPrimal, "primal"}, {Term::kDx, "dx"}, {Term::kDy, "dy"}}) {
      gf.buffer(t) = f.image.find(n)->image;
      gf.variance(t) = f.image.find(std::string(n) + "_var")->image;
    }
    ReconSettings rs;
    rs.method = ReconMethod::kL2;
    rs.alpha = job.reconstruction.alpha;
    auto solved = reconstruct_frame(gf, rs);
    ASSERT_TRUE(solved.ok());
    const Image& fin = f.image.find("")->image;
    const Image& direct = f.image.find("direct")->image;
    for (size_t k = 0; k < fin.data().size(); ++k)
      ASSERT_EQ(fin.data()[k], std::max(solved->frames[0].data()[k] + direct.data()[k], 0.0f)) << "frame " << f.frame;
    // The temporal layers are still sampled (and finite) for frames with a successor.
    if (f.frame < 2) {
      double sum = 0;
      for (float v : f.image.find("dt")->image.data()) sum += std::abs(v);
      EXPECT_GT(sum, 0.0);
    }
  }
}

// The job's per-term weights reach the window solve: with the temporal terms
// weighted 0 a 3-frame window gives each frame's spatial solve (W = 1).
TEST_P(TgptJobTest, TermWeightsReachTheSolve) {
  JobSpec windowed = tgpt_job(GetParam(), "0-2", true, 3);
  windowed.reconstruction.term_weights = {1, 1, 1, 0, 0, 0};
  auto a = run(windowed);
  auto b = run(tgpt_job(GetParam(), "0-2", true, 1));
  auto c = run(tgpt_job(GetParam(), "0-2", true, 3));
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  ASSERT_EQ(c.size(), 3u);
  // Relative L2 differences over the shot: the two solves stop at the same
  // relative residual (1e-3) of differently sized systems, so they agree to
  // that order, not bit for bit.
  double d_ab = 0, d_cb = 0, n_b = 0;
  for (size_t f = 0; f < 3; ++f) {
    const auto& ia = a[f].image.find("")->image.data();
    const auto& ib = b[f].image.find("")->image.data();
    const auto& ic = c[f].image.find("")->image.data();
    for (size_t k = 0; k < ia.size(); ++k) {
      d_ab += (double(ia[k]) - ib[k]) * (double(ia[k]) - ib[k]);
      d_cb += (double(ic[k]) - ib[k]) * (double(ic[k]) - ib[k]);
      n_b += double(ib[k]) * ib[k];
    }
  }
  const double rel_ab = std::sqrt(d_ab / n_b), rel_cb = std::sqrt(d_cb / n_b);
  std::printf("[ term weights ] temporal weights 0 vs W = 1: %.3e; weights 1 vs W = 1: %.6e\n", rel_ab, rel_cb);
  EXPECT_LT(rel_ab, 2e-3);
  EXPECT_GT(rel_cb, 5 * rel_ab) << "the temporal terms must matter when weighted 1";
}

TEST_P(TgptJobTest, TwoFrameShotAndWindowLongerThanShot) {
  for (int window : {2, 20}) {
    auto out = run(tgpt_job(GetParam(), "0-1", true, window));
    ASSERT_EQ(out.size(), 2u) << window;
    EXPECT_EQ(out[0].frame, 0);
    EXPECT_EQ(out[1].frame, 1);
    for (const FrameOutput& f : out) {
      expect_finite_layers(f);
      for (const char* name : {"", "primal", "dx", "dy", "dt", "dxdt", "dydt", "direct", "temporal_failure_rate",
                               "shift_failure_rate", "motion"})
        EXPECT_NE(f.image.find(name), nullptr) << name;
      EXPECT_EQ(f.stats.spp, 4);
    }
  }
}

TEST_P(TgptJobTest, SingleFrameJobHasNoTemporalBuffers) {
  auto out = run(tgpt_job(GetParam(), "3", true, 20));
  ASSERT_EQ(out.size(), 1u);
  expect_finite_layers(out[0]);
  for (const char* name : {"dt", "dxdt", "dydt", "temporal_failure_rate", "motion"})
    EXPECT_EQ(out[0].image.find(name), nullptr) << name;
  EXPECT_NE(out[0].image.find("primal"), nullptr);
  EXPECT_TRUE(has(out[0].stats.left_out, "temporal gradients and buffers: single-frame job"));
}

// Frames come out in order, each as soon as its windows are rendered, and a
// stand-alone finalize of each frame (a farm's stage 2) gives the same image.
TEST_P(TgptJobTest, SpilledBuffersAndTilesGiveTheFramesOfMemory) {
  // 32x32 frames in 16-pixel tiles (2x2): each window solved by tiles; every
  // buffered frame spilled to disk (memory limit 0) must change nothing.
  JobSpec job = tgpt_job(GetParam(), "0-6", true, 4);
  job.width = job.height = 32;
  job.reconstruction.tile_size = 16;
  const std::vector<FrameOutput> in_memory = run(job);
  const std::vector<FrameOutput> spilled = run(job, /* memory_limit_bytes = */ 0);
  ASSERT_EQ(in_memory.size(), 7u);
  ASSERT_EQ(spilled.size(), 7u);
  for (size_t i = 0; i < 7; ++i) {
    ASSERT_EQ(spilled[i].image.layers.size(), in_memory[i].image.layers.size());
    for (size_t l = 0; l < in_memory[i].image.layers.size(); ++l)
      EXPECT_EQ(spilled[i].image.layers[l].image.data(), in_memory[i].image.layers[l].image.data())
          << "frame " << i << " layer " << in_memory[i].image.layers[l].name;
    expect_finite_layers(spilled[i]);
  }
  // And the tiles agree with the whole-frame windows.
  job.reconstruction.tile_size = 0;
  const std::vector<FrameOutput> whole = run(job);
  ASSERT_EQ(whole.size(), 7u);
  for (size_t i = 0; i < 7; ++i) {
    auto e = rel_mse_sums(in_memory[i].image.find("")->image, whole[i].image.find("")->image);
    ASSERT_TRUE(e.ok());
    EXPECT_LE(e->global(), 1e-6) << "frame " << i;
  }
}

TEST_P(TgptJobTest, StreamsInOrderAndStagesAgree) {
  JobSpec job = tgpt_job(GetParam(), "0-6", true, 4);
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.threads = 2;
  std::vector<FrameOutput> out;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& f) { out.push_back(f); };
  Status st = run_job(job, options, cb, nullptr);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(out.size(), 7u);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(out[size_t(i)].frame, i);

  std::map<int, FrameBuffers> buffers;
  std::vector<int> all = {0, 1, 2, 3, 4, 5, 6};
  ASSERT_TRUE(render_job_buffers(job, options, all, [&](FrameBuffers&& b) {
                buffers[b.frame] = std::move(b);
                return Status::Ok();
              }, nullptr, nullptr).ok());
  for (int f : all) {
    std::map<int, FrameBuffers> needed;
    for (int k : frames_needed_to_finalize(job, all, f)) needed[k] = buffers[k];
    EXPECT_LE(needed.size(), 4u + 2u + 1u);
    auto fin = finalize_frame(job, f, needed);
    ASSERT_TRUE(fin.ok()) << fin.status().to_string();
    const auto& a = fin->image.find("")->image.data();
    const auto& b = out[size_t(f)].image.find("")->image.data();
    ASSERT_EQ(a, b) << "frame " << f;
    // Missing buffers are an error naming the frame, not a crash.
    std::map<int, FrameBuffers> partial = needed;
    partial.erase(partial.rbegin()->first);
    EXPECT_FALSE(finalize_frame(job, f, partial).ok());
  }
  // A farm task's finalizer gives the same images and solves each window once
  // (7 frames, W = 4, H = 2: windows [0,4) [2,6) [4,7)); frame by frame solves
  // each window once for every frame it holds.
  auto finalizer = JobFinalizer::create(job);
  ASSERT_TRUE(finalizer.ok()) << finalizer.status().to_string();
  for (int f : all) {
    auto fin = finalizer.value()->finalize(f, buffers);
    ASSERT_TRUE(fin.ok()) << fin.status().to_string();
    ASSERT_EQ(fin->image.find("")->image.data(), out[size_t(f)].image.find("")->image.data()) << "frame " << f;
  }
  EXPECT_EQ(finalizer.value()->windows_solved(), 3);
  // Out of order, a window let go is solved again, and the images stay the same.
  auto again = finalizer.value()->finalize(1, buffers);
  ASSERT_TRUE(again.ok()) << again.status().to_string();
  EXPECT_EQ(again->image.find("")->image.data(), out[1].image.find("")->image.data());
  EXPECT_EQ(finalizer.value()->windows_solved(), 4);
  // Moving pairs carry motion fields and count temporal failures somewhere.
  EXPECT_NE(buffers[0].layers.find("motion"), nullptr);
  EXPECT_NE(buffers[1].layers.find("motion_back"), nullptr);
  // The path-space shift's two generations: forward from every frame but the
  // last, backward from every frame but the first.
  const bool reconnect = GetParam() == "reconnect";
  for (int f : all) {
    EXPECT_GT(buffers[f].stats.temporal_rays, 0u) << f;
    EXPECT_EQ(buffers[f].layers.find("dt_fwd") != nullptr, reconnect && f < 6) << f;
    EXPECT_EQ(buffers[f].layers.find("dt_bwd") != nullptr, reconnect && f > 0) << f;
  }
}

INSTANTIATE_TEST_SUITE_P(TemporalShift, TgptJobTest, ::testing::Values("replay", "reconnect"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace gdvr
