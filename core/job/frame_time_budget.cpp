#include "core/job/frame_time_budget.h"

#include <algorithm>
#include <cmath>

namespace gdvr {

FrameTimeBudget::FrameTimeBudget(double budget_s, int frames, double stage2_prior_s, double caller_prior_s)
    : budget_s_(budget_s),
      frames_(std::max(frames, 1)),
      stage2_prior_s_(std::max(stage2_prior_s, 0.0)),
      caller_prior_s_(std::max(caller_prior_s, 0.0)) {}

FrameTimeBudget FrameTimeBudget::stage1_only(double budget_s, int frames) {
  FrameTimeBudget budget(budget_s, frames);
  budget.pays_stage2_ = false;
  return budget;
}

double FrameTimeBudget::finalize_seconds_per_frame() const {
  return finalized_frames_ > 0 ? finalize_seconds_ / finalized_frames_ : stage2_prior_s_ + caller_prior_s_;
}

// Wall time spent so far, with stage 2's lumps replaced by their rate per
// rendered frame: a window solved after its last frame is not a deficit of
// the frames before it, it is what they reserved.
double FrameTimeBudget::ledger_spent(double now) const {
  return now - finalize_seconds_ + finalize_seconds_per_frame() * frames_done_;
}

void FrameTimeBudget::begin_frame(double now) {
  frame_begin_ = now;
  this_frame_ = Sampling{};
  this_frame_one_off_ = 0;
}

void FrameTimeBudget::plan_frame(double now) {
  frame_plan_ = now;
  const double credit = budget_s_ * frames_done_ - ledger_spent(frame_begin_);
  const int left = std::max(frames_ - frames_done_, 1);
  // Paid back over a few frames, and at most half a budget per frame, so that
  // one slow frame (another process's burst) does not halve the next one's count.
  const double spread = std::clamp(credit / std::min(left, kCatchUpFrames), -0.5 * budget_s_, 0.5 * budget_s_);
  const double spent_this_frame = now - frame_begin_;
  render_allowance_ = std::max(0.0, budget_s_ + spread - spent_this_frame - finalize_seconds_per_frame());
  sampling_allowance_ = std::max(0.0, render_allowance_ - fixed_render_);
}

void FrameTimeBudget::end_frame(double now) {
  // What the render cost besides its sampling (direct light, motion vectors,
  // the runner's bookkeeping): a running mean over the last few frames.
  const double fixed = std::max(0.0, (now - frame_plan_) - this_frame_.seconds - this_frame_one_off_);
  fixed_frames_ = std::min(fixed_frames_ + 1, kCostFrames);
  fixed_render_ += (fixed - fixed_render_) / fixed_frames_;
  if (this_frame_.samples > 0) {
    sampling_.push_back(this_frame_);
    cost_samples_ += this_frame_.samples;
    cost_seconds_ += this_frame_.seconds;
    while (int(sampling_.size()) > kCostFrames) {
      cost_samples_ -= sampling_.front().samples;
      cost_seconds_ -= sampling_.front().seconds;
      sampling_.pop_front();
    }
  }
  this_frame_ = Sampling{};
  this_frame_one_off_ = 0;
  ++frames_done_;
}

void FrameTimeBudget::record_finalize(int frames, double seconds) {
  if (frames <= 0) return;
  finalized_frames_ += frames;
  finalize_seconds_ += std::max(seconds, 0.0);
}

void FrameTimeBudget::record_sampling(int samples, double seconds) {
  if (samples <= 0) return;
  this_frame_.samples += samples;
  this_frame_.seconds += std::max(seconds, 0.0);
}

double FrameTimeBudget::seconds_per_sample() const {
  const double samples = cost_samples_ + this_frame_.samples;
  return samples > 0 ? (cost_seconds_ + this_frame_.seconds) / samples : 0.0;
}

double FrameTimeBudget::samples_in(double seconds) const {
  const double cost = seconds_per_sample();
  return cost > 0 ? std::max(seconds, 0.0) / cost : 0.0;
}

int FrameTimeBudget::take_count(double samples, int unit) {
  unit = std::max(unit, 1);
  const double want = std::max(samples, 0.0) / unit + count_residual_;
  const int units = std::max(1, int(std::floor(want)));
  count_residual_ = std::clamp(want - units, 0.0, 1.0);
  return units * unit;
}

}  // namespace gdvr
