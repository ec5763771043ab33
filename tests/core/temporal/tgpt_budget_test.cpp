// T-GPT under a time budget (core/job/frame_time_budget.h): pass B of frame t
// and pass A of frame t+1 replay the same random numbers, so they must take
// the same sample count for dt = A_{t+1} − B_t to be a correlated
// difference. These tests assert the pairing, not any timing: whatever
// counts the budget picks on this machine, they must pair.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "core/job/frame_time_budget.h"
#include "core/job/integrators/tgpt_runner.h"
#include "core/job/job_runner.h"
#include "core/temporal/denoised_data_term.h"
#include "core/temporal/temporal_buffers.h"

namespace gdvr {
namespace {

std::string demo_dir() { return std::string(GDVR_SOURCE_DIR) + "/scenes/demo"; }

JobSpec budgeted_job(const std::string& frames, double budget) {
  JobSpec job;
  job.scene = "cbox_demo.xml";
  job.frames = frames;
  job.fps = 24;
  job.width = job.height = 24;
  job.seed = 9;
  job.integrator = Integrator::kTgpt;
  job.reconstruction.method = ReconMethod::kL2;
  job.reconstruction.window = 4;
  job.time_budget_s = budget;
  job.spp = 0;
  return job;
}

// The box and the camera move: every pair changes, every pass A is rendered.
void animate(JobSpec* job) {
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  job->animation.tracks.push_back(box);
  Track cam;
  cam.target = "sensor";
  Transform a, b;
  ASSERT_TRUE(Transform::look_at({278, 273, -800}, {278, 273, -799}, {0, 1, 0}, &a));
  ASSERT_TRUE(Transform::look_at({250, 280, -680}, {275, 265, 0}, {0, 1, 0}, &b));
  cam.keys = {Keyframe{0.0, a}, Keyframe{2.0, b}};
  job->animation.tracks.push_back(cam);
}

// The large box "moves" by 1e-30 scene units: every pair counts as changed
// (transforms are compared exactly), so pass A is rendered and dt is formed by
// subtraction, but in float the box stays where it was, so the scene is the
// same bit for bit and a replayed pair at equal counts is the same image.
void move_invisibly(JobSpec* job) {
  Track box;
  box.target = "largebox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({1e-30f, 0, 0})}};
  job->animation.tracks.push_back(box);
}

std::map<int, FrameBuffers> render(const JobSpec& job, const std::vector<int>& frames) {
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.threads = 2;
  std::map<int, FrameBuffers> out;
  Status st = render_job_buffers(
      job, options, frames,
      [&](FrameBuffers&& b) {
        out[b.frame] = std::move(b);
        return Status::Ok();
      },
      nullptr, nullptr);
  EXPECT_TRUE(st.ok()) << st.to_string();
  return out;
}

TEST(TgptBudgetTest, PassAOfEveryFrameHasTheCountOfThePreviousPassB) {
  JobSpec job = budgeted_job("0-7", 0.05);
  animate(&job);
  std::vector<FrameOutput> out;
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.threads = 2;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& f) { out.push_back(f); };
  ASSERT_TRUE(run_job(job, options, cb, nullptr).ok());
  ASSERT_EQ(out.size(), 8u);
  for (size_t i = 0; i < out.size(); ++i) {
    const FrameStats& s = out[i].stats;
    SCOPED_TRACE("frame " + std::to_string(s.frame));
    EXPECT_GE(s.pass_a_spp, 1);
    EXPECT_GE(s.pass_b_spp, 1);
    EXPECT_EQ(s.spp, s.pass_a_spp + s.pass_b_spp);
    if (i > 0) {
      EXPECT_EQ(s.pass_a_spp, out[i - 1].stats.pass_b_spp);
    }
    EXPECT_GT(s.stage1_seconds, 0.0);
    EXPECT_LE(s.sampling_seconds, s.render_seconds);
  }
}

// With the pairs at equal counts, a pair whose scene did not really change
// replays to the same image: B_t and A_{t+1} equal bit for bit and dt is
// exactly 0, though it was formed by subtraction.
TEST(TgptBudgetTest, BudgetedDtIsTheReplayedDifference) {
  JobSpec job = budgeted_job("0-5", 0.05);
  move_invisibly(&job);
  auto buffers = render(job, {0, 1, 2, 3, 4, 5});
  ASSERT_EQ(buffers.size(), 6u);
  for (int t = 0; t + 1 < 6; ++t) {
    SCOPED_TRACE("pair " + std::to_string(t));
    EXPECT_EQ(buffers[t + 1].stats.pass_a_spp, buffers[t].stats.pass_b_spp);
    EXPECT_EQ(buffers[t].layers.find("b_primal")->image.data(), buffers[t + 1].layers.find("a_primal")->image.data());
    auto tg = temporal_gradients(buffers[t].layers, buffers[t + 1].layers, TgptSettings{});
    ASSERT_TRUE(tg.ok()) << tg.status().to_string();
    EXPECT_FALSE(tg->static_pair) << "the pair must count as changed, or dt is not subtracted";
    EXPECT_EQ(tg->failed, 0);
    for (float v : tg->dt.data()) ASSERT_EQ(v, 0.0f);
  }
}

// What the test above guards against: the same pair at different counts (two
// processes, 2 and 4 spp per frame) is not the same image, and dt is not 0.
TEST(TgptBudgetTest, UnequalCountsBreakTheReplay) {
  JobSpec job = budgeted_job("0-1", 0);
  move_invisibly(&job);
  job.spp = 2;
  auto first = render(job, {0});
  job.spp = 4;
  auto second = render(job, {1});
  ASSERT_EQ(first[0].stats.pass_b_spp, 1);
  ASSERT_EQ(second[1].stats.pass_a_spp, 2);
  auto tg = temporal_gradients(first[0].layers, second[1].layers, TgptSettings{});
  ASSERT_TRUE(tg.ok());
  double sum_sq = 0;
  for (float v : tg->dt.data()) sum_sq += double(v) * v;
  EXPECT_GT(sum_sq, 0.0);
}

// Across static pairs under a budget pass A is the previous pass B, copied
// (the counts pair, so the copy is the pass it replaces).
TEST(TgptBudgetTest, StaticPairsReusePassAUnderABudget) {
  JobSpec job = budgeted_job("0-3", 0.05);
  auto buffers = render(job, {0, 1, 2, 3});
  ASSERT_EQ(buffers.size(), 4u);
  for (int t = 1; t < 4; ++t) {
    SCOPED_TRACE("frame " + std::to_string(t));
    bool copied = false;
    for (const std::string& l : buffers[t].stats.left_out) copied = copied || l.rfind("pass A: equals", 0) == 0;
    EXPECT_TRUE(copied);
    EXPECT_EQ(buffers[t].stats.pass_a_spp, buffers[t - 1].stats.pass_b_spp);
  }
}

// The caller's work on a final frame counts in the budget. T-GPT's frames
// come out only when their window is solved, so the caller is asked once,
// after the first frame, what it will cost; PT's come out at once and are
// measured instead.
TEST(TgptBudgetTest, TheCallersOutputIsEstimatedOnceWhereFramesWait) {
  for (Integrator integrator : {Integrator::kTgpt, Integrator::kPt}) {
    JobSpec job = budgeted_job("0-3", 0.02);
    job.integrator = integrator;
    animate(&job);
    JobRunOptions options;
    options.base_dir = demo_dir();
    options.threads = 2;
    int asked = 0, final_before_asked = 0, final_frames = 0;
    JobCallbacks cb;
    cb.on_frame_final = [&](const FrameOutput&) { ++final_frames; };
    cb.estimate_frame_final_seconds = [&](const FrameBuffers& buffers) {
      ++asked;
      final_before_asked = final_frames;
      EXPECT_EQ(buffers.frame, 0);
      return 0.001;
    };
    ASSERT_TRUE(run_job(job, options, cb, nullptr).ok());
    EXPECT_EQ(final_frames, 4);
    if (integrator == Integrator::kTgpt) {
      EXPECT_EQ(asked, 1);
      EXPECT_EQ(final_before_asked, 0);
    } else {
      EXPECT_EQ(asked, 0) << "pt's frames come out at once: measured, not estimated";
    }
  }
}


// The window solve's cost is unknown until the shot's first window is in, so
// T-GPT times a two-frame window of the first frame's buffers, once, and only
// when the frame is complete: the solve it times must be the one stage 2 will
// run, denoised data term included (calibrated before that term was added,
// it solved another problem and over-reserved up to 2x on a caustic scene).
TEST(TgptBudgetTest, TheWindowSolveIsCalibratedOnceOnTheFinishedFrame) {
  JobSpec job = budgeted_job("0-3", 0.3);
  job.reconstruction.method = ReconMethod::kL1;
  animate(&job);
  std::map<int, FrameBuffers> buffers = render(job, {0});
  ASSERT_EQ(buffers.count(0), 1u);
  LayeredImage layers = buffers[0].layers;
  // A data term as add_denoised_data_term leaves it: the image and its trust.
  auto primal = tgpt_frame_estimate(layers, "primal");
  ASSERT_TRUE(primal.ok()) << primal.status().to_string();
  layers.add(kDenoisedPrimalLayer, {"R", "G", "B"}, primal.value());
  Image ones(primal->width(), primal->height(), 1);
  for (float& v : ones.data()) v = 1.0f;
  layers.add(kDataWeightLayer, {"Y"}, ones);

  constexpr double kPrior = 100.0;  // what the budget holds before any calibration
  auto fresh_runner = [&] {
    auto runner = TgptRunner::create(job, {0, 1, 2, 3});
    EXPECT_TRUE(runner.ok()) << runner.status().to_string();
    return std::move(runner.value());
  };

  // A render task's budget pays no stage 2: nothing is timed, and the
  // runner can still calibrate later.
  auto runner = fresh_runner();
  FrameTimeBudget render_only = FrameTimeBudget::stage1_only(0.3, 4);
  runner->calibrate_stage2(layers, &render_only);
  EXPECT_EQ(render_only.finalize_seconds_per_frame(), 0.0);

  FrameTimeBudget budget(0.3, 4, kPrior);
  EXPECT_EQ(budget.finalize_seconds_per_frame(), kPrior);
  runner->calibrate_stage2(layers, &budget);
  const double calibrated = budget.finalize_seconds_per_frame();
  EXPECT_GT(calibrated, 0.0);
  EXPECT_LT(calibrated, kPrior) << "the measured solve replaces the prior";
  runner->calibrate_stage2(layers, &budget);
  EXPECT_EQ(budget.finalize_seconds_per_frame(), calibrated) << "calibrated once per job";

  // The calibration reads the data term's layers: a trust map of the wrong
  // shape makes the frame invalid, and the prior stays (stage 2 will report it).
  LayeredImage broken = buffers[0].layers;
  broken.add(kDenoisedPrimalLayer, {"R", "G", "B"}, primal.value());
  broken.add(kDataWeightLayer, {"Y"}, Image(2, 2, 1));
  FrameTimeBudget untouched(0.3, 4, kPrior);
  fresh_runner()->calibrate_stage2(broken, &untouched);
  EXPECT_EQ(untouched.finalize_seconds_per_frame(), kPrior);
}

}  // namespace
}  // namespace gdvr
