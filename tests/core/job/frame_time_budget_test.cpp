// The time-budget account (core/job/frame_time_budget.h) fed with made-up
// costs on a simulated clock: no timing, so every figure is exact.
#include "core/job/frame_time_budget.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace gdvr {
namespace {

// A simulated job: every frame spends `features` before its sampling, the
// sampling costs `per_sample` a sample, the render adds `render_fixed`, and
// stage 2 costs `finalize` per frame, paid in lumps of `lump` frames (1: each
// frame right after its render, as pt and gpt; the shot length: T-GPT's one
// window at the end).
struct SimulatedJob {
  double budget = 1.0;
  int frames = 12;
  double features = 0.05, render_fixed = 0.03, per_sample = 0.02, finalize = 0.1, finalize_prior = 0.1;
  int lump = 1;
  double startup = 0;  // before the first frame (scene loading)

  struct Result {
    std::vector<int> counts;
    double wall = 0;
  };
  Result run() const {
    FrameTimeBudget budget(this->budget, frames, finalize_prior);
    Result r;
    double now = startup;
    int pending = 0;
    for (int f = 0; f < frames; ++f) {
      budget.begin_frame(now);
      now += features;
      budget.plan_frame(now);
      int spp;
      if (!budget.has_sample_cost()) {
        // Against the clock: whole samples while the next one fits.
        spp = std::max(1, int(std::floor((budget.render_seconds() - render_fixed) / per_sample)));
      } else {
        spp = budget.take_count(budget.samples_in(budget.sampling_seconds()));
      }
      budget.record_sampling(spp, spp * per_sample);
      now += spp * per_sample + render_fixed;
      budget.end_frame(now);
      r.counts.push_back(spp);
      if (++pending == lump || f + 1 == frames) {
        now += pending * finalize;
        budget.record_finalize(pending, pending * finalize);
        pending = 0;
      }
    }
    r.wall = now;
    return r;
  }
};

// The largest minus the smallest count from frame `from` on.
int spread(const std::vector<int>& counts, size_t from) {
  int lo = counts[from], hi = counts[from];
  for (size_t f = from; f < counts.size(); ++f) lo = std::min(lo, counts[f]), hi = std::max(hi, counts[f]);
  return hi - lo;
}

TEST(FrameTimeBudgetTest, SteadyCostsGiveASteadyCountAndTheBudget) {
  SimulatedJob job;  // 1 s: 0.05 features + 0.03 render + 0.1 finalize leave 0.82 s = 41 samples
  auto r = job.run();
  for (size_t f = 1; f < r.counts.size(); ++f) EXPECT_NEAR(r.counts[f], 41, 1) << "frame " << f;
  EXPECT_LE(spread(r.counts, 1), 2);
  EXPECT_NEAR(r.wall / job.frames, job.budget, 0.02 * job.budget);
}

TEST(FrameTimeBudgetTest, FractionalTargetsAreDitheredNotRoundedDown) {
  SimulatedJob job;
  job.per_sample = 0.82 / 4.5;  // 4.5 samples fit: 4 and 5 alternate, never 4 forever
  job.frames = 40;
  auto r = job.run();
  int fours = 0, fives = 0;
  for (size_t f = 1; f < r.counts.size(); ++f) {
    EXPECT_TRUE(r.counts[f] == 4 || r.counts[f] == 5) << "frame " << f << ": " << r.counts[f];
    fours += r.counts[f] == 4;
    fives += r.counts[f] == 5;
  }
  EXPECT_GT(fours, 10);
  EXPECT_GT(fives, 10);
  EXPECT_NEAR(r.wall / job.frames, job.budget, 0.03 * job.budget);
}

// Features, the render's fixed part and stage 2 are all paid from the budget.
TEST(FrameTimeBudgetTest, FixedCostsComeOffTheSampling) {
  SimulatedJob cheap, dear;
  dear.features = 0.2;
  dear.finalize = dear.finalize_prior = 0.3;
  auto a = cheap.run(), b = dear.run();
  EXPECT_NEAR(a.counts.back(), 41, 1);  // (1 - 0.05 - 0.03 - 0.1) / 0.02
  EXPECT_NEAR(b.counts.back(), 23.5, 1.5);  // (1 - 0.2 - 0.03 - 0.3) / 0.02
  EXPECT_NEAR(a.wall / cheap.frames, cheap.budget, 0.02 * cheap.budget);
  EXPECT_NEAR(b.wall / dear.frames, dear.budget, 0.02 * dear.budget);
}

// T-GPT's window solve comes after the shot's last render: only the prior
// reserved for it keeps the shot on budget, and the ledger does not spend the
// reserve early.
TEST(FrameTimeBudgetTest, ALumpAtTheEndIsReservedFromEveryFrame) {
  SimulatedJob job;
  job.lump = job.frames;
  job.finalize = job.finalize_prior = 0.25;
  auto r = job.run();
  EXPECT_LE(spread(r.counts, 1), 1) << "the reserve for the solve is not spent early";
  EXPECT_NEAR(r.counts.back(), 33.5, 1);  // (1 - 0.05 - 0.03 - 0.25) / 0.02
  EXPECT_NEAR(r.wall / job.frames, job.budget, 0.02 * job.budget);
  // Without the prior the lump lands on top of the budget.
  job.finalize_prior = 0;
  auto blind = job.run();
  EXPECT_GT(blind.wall / job.frames, 1.2 * job.budget);
}

// A lump measured in the middle of a shot sets the rate for the frames after
// it (and the deficit of a too small prior is paid back).
TEST(FrameTimeBudgetTest, MeasuredLumpsReplaceThePrior) {
  SimulatedJob job;
  job.frames = 48;
  job.lump = 10;
  job.finalize = 0.2;
  job.finalize_prior = 0.05;
  auto r = job.run();
  EXPECT_NEAR(r.wall / job.frames, job.budget, 0.03 * job.budget);
  // After the first lumps the rate is measured: (1 - 0.05 - 0.03 - 0.2) / 0.02 = 36.
  for (size_t f = 24; f < r.counts.size(); ++f) EXPECT_NEAR(r.counts[f], 36, 2) << "frame " << f;
}

// Startup (scene loading) and a slow frame are paid back over the next few
// frames, not all at once.
TEST(FrameTimeBudgetTest, DeficitsArePaidBackGradually) {
  SimulatedJob job;
  job.startup = 0.6;
  auto r = job.run();
  EXPECT_NEAR(r.wall / job.frames, job.budget, 0.02 * job.budget);
  for (size_t f = 1; f < r.counts.size(); ++f) EXPECT_GE(r.counts[f], 41 - 16) << "frame " << f << " starved";
}

// A budget smaller than the fixed costs still samples: one unit per frame.
TEST(FrameTimeBudgetTest, HopelessBudgetStillRendersOnePass) {
  FrameTimeBudget budget(0.1, 4, 0.5);
  budget.begin_frame(0);
  budget.plan_frame(0.05);
  EXPECT_EQ(budget.render_seconds(), 0.0);
  budget.record_sampling(1, 0.01);
  EXPECT_EQ(budget.take_count(budget.samples_in(budget.sampling_seconds()), 4), 4);
}

TEST(FrameTimeBudgetTest, CountsAreMultiplesOfThePassSize) {
  FrameTimeBudget budget(1, 10);
  EXPECT_EQ(budget.take_count(10, 4), 8);   // 2.5 passes: 2, carry 0.5
  EXPECT_EQ(budget.take_count(10, 4), 12);  // 3.0 passes
  EXPECT_EQ(budget.take_count(10, 4), 8);
}

TEST(FrameTimeBudgetTest, CostPerSampleAveragesTheRecentFrames) {
  FrameTimeBudget budget(1, 100);
  EXPECT_FALSE(budget.has_sample_cost());
  double now = 0;
  for (int f = 0; f < 10; ++f) {
    budget.begin_frame(now);
    budget.plan_frame(now);
    budget.record_sampling(10, f < 5 ? 1.0 : 2.0);  // the machine got twice as slow at frame 5
    now += 2;
    budget.end_frame(now);
  }
  EXPECT_TRUE(budget.has_sample_cost());
  EXPECT_DOUBLE_EQ(budget.seconds_per_sample(), 0.2);  // only the last kCostFrames frames count
}

// A farm's render task: stage 2 runs in another process, so nothing is
// reserved for it, whatever a runner would calibrate.
TEST(FrameTimeBudgetTest, RenderOnlyTasksReserveNothingForStage2) {
  FrameTimeBudget budget = FrameTimeBudget::stage1_only(1.0, 4);
  EXPECT_FALSE(budget.pays_stage2());
  budget.set_stage2_prior(0.4);
  budget.set_caller_prior(0.1);
  budget.begin_frame(0);
  budget.plan_frame(0);
  EXPECT_DOUBLE_EQ(budget.render_seconds(), 1.0);
  FrameTimeBudget full(1.0, 4);
  full.set_stage2_prior(0.4);
  full.set_caller_prior(0.1);
  full.begin_frame(0);
  full.plan_frame(0);
  EXPECT_DOUBLE_EQ(full.render_seconds(), 0.5);
}

}  // namespace
}  // namespace gdvr
