// A job's time budget per frame (`time_budget_s`) as one account that every
// integrator draws on (docs/renderer.md, "Time budgets"). The budget bounds
// what the user waits for per frame: the sampling, the direct-light pass, the
// feature buffers, T-GPT's motion vectors, the reconstruction (G-PT's solve
// per frame, T-GPT's window solves spread over the frames) and whatever the
// caller does with each final frame (writing it, denoising it). Only the
// sampling can give; everything else is a fixed cost this account measures
// and takes off the budget before the sampling gets the rest.
//
// The account is a pure function of what it is told (no clock of its own):
// the job runner feeds it its wall clock at the frame's milestones, the
// integrator the seconds and samples of its sampling passes, so its decisions
// can be tested with made-up costs (tests/core/job/frame_time_budget_test.cpp).
//
// Three rules keep a budgeted frame as good as the same time spent at a fixed
// spp:
//  - counts, not deadlines: after the first frame the integrator renders a
//    sample count chosen before the frame (from the measured seconds per
//    sample), so T-GPT can give pass A of frame t+1 exactly the count of pass
//    B of frame t (core/temporal/pass_schedule.h: they replay the same random
//    numbers, and dt = A_{t+1} − B_t is a correlated difference only at equal
//    counts);
//  - steady counts: the count is the allowance over the measured cost per
//    sample, dithered (error diffusion: a target of 4.5 gives 4, 5, 4, 5, ...)
//    so the mean hits the budget without the count jumping;
//  - a ledger: the wall time spent so far against budget × frames done, the
//    difference spread over the next few frames, so a misprediction (load
//    from other processes, the first frame's scene loading) is paid back
//    rather than carried. Lumpy costs (T-GPT solves a window once its frames
//    are in; finalized frames come out in bursts) enter the ledger at their
//    predicted rate per frame, measured from the lumps seen so far and, before
//    the first, a prior the caller gives (T-GPT's calibrated solve cost).
#pragma once

#include <deque>

namespace gdvr {

class FrameTimeBudget {
 public:
  // Frames the ledger spreads a surplus or deficit over (at most the frames left).
  static constexpr int kCatchUpFrames = 4;
  // Frames whose sampling costs the seconds-per-sample estimate averages.
  static constexpr int kCostFrames = 4;

  // `budget_s` seconds per frame for `frames` frames. `stage2_prior_s` and
  // `caller_prior_s`: the predicted seconds per frame of stage 2 and of what
  // the caller does with a final frame, used until the first finalized frame
  // is measured (their sum is the rate until then).
  FrameTimeBudget(double budget_s, int frames, double stage2_prior_s = 0, double caller_prior_s = 0);
  // A process that only renders (a farm's render task): stage 2 runs
  // elsewhere, so nothing is reserved for it and a prior is not calibrated.
  static FrameTimeBudget stage1_only(double budget_s, int frames);

  double budget_s() const { return budget_s_; }
  bool pays_stage2() const { return pays_stage2_; }

  // ---- The job runner, on its wall clock (seconds since the job began) ----
  // A frame's stage 1 begins; the fixed costs it spends before its
  // sampling (the feature pass) come between this and plan_frame.
  void begin_frame(double now);
  // The integrator is about to render: fixes the frame's allowance.
  void plan_frame(double now);
  // The frame's stage 1 is done (render and features).
  void end_frame(double now);
  // Stage 2 finalized `frames` frames and handed them on in `seconds`.
  void record_finalize(int frames, double seconds);
  // Better guesses than those given at the start (T-GPT calibrates its
  // window solve on the first frame's buffers; a caller may time its output
  // on them), still replaced by the measured rate once frames are finalized.
  void set_stage2_prior(double seconds_per_frame) {
    if (pays_stage2_) stage2_prior_s_ = seconds_per_frame > 0 ? seconds_per_frame : 0;
  }
  void set_caller_prior(double seconds_per_frame) {
    if (pays_stage2_) caller_prior_s_ = seconds_per_frame > 0 ? seconds_per_frame : 0;
  }

  // ---- The integrator, between plan_frame and end_frame ----
  // Seconds its render (direct-light pass, sampling, motion vectors) may take.
  double render_seconds() const { return render_allowance_; }
  // Of which the sampling passes' share (the render less its measured fixed part).
  double sampling_seconds() const { return sampling_allowance_; }
  // Whether a seconds-per-sample estimate exists (false before the first
  // sampling was recorded: the first frame then renders against the clock).
  bool has_sample_cost() const { return cost_samples_ + this_frame_.samples > 0; }
  // Samples per pixel that fit `seconds` at the measured cost.
  double samples_in(double seconds) const;
  // A whole count of `unit`-spp passes for a target of `samples` spp: at
  // least one unit, the fraction carried to the next call (error diffusion).
  int take_count(double samples, int unit = 1);
  // Sampling passes measured: `samples` spp took `seconds`.
  void record_sampling(int samples, double seconds);
  // Seconds of this frame's render that later frames will not spend again
  // (a calibration): kept out of the render's fixed cost per frame.
  void record_one_off(double seconds) { this_frame_one_off_ += seconds > 0 ? seconds : 0; }

  // ---- What the account holds (tests, reports) ----
  double seconds_per_sample() const;
  double fixed_render_seconds() const { return fixed_render_; }  // render less sampling, per frame
  double finalize_seconds_per_frame() const;
  int frames_done() const { return frames_done_; }

 private:
  double ledger_spent(double now) const;

  double budget_s_;
  int frames_;
  double stage2_prior_s_, caller_prior_s_;
  bool pays_stage2_ = true;

  int frames_done_ = 0;
  double frame_begin_ = 0, frame_plan_ = 0;
  double render_allowance_ = 0, sampling_allowance_ = 0;

  // Sampling cost: the last kCostFrames frames' samples and seconds (a frame
  // may record several passes; they are summed into its entry).
  struct Sampling {
    double samples = 0, seconds = 0;
  };
  std::deque<Sampling> sampling_;
  double cost_samples_ = 0, cost_seconds_ = 0;
  Sampling this_frame_;
  double this_frame_one_off_ = 0;

  double fixed_render_ = 0;  // measured render seconds outside the sampling, averaged
  int fixed_frames_ = 0;
  double finalize_seconds_ = 0;
  int finalized_frames_ = 0;

  double count_residual_ = 0;
};

}  // namespace gdvr
