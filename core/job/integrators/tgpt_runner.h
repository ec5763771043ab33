// Temporal gradient-domain path tracing in a job (docs/tgpt.md): stage 1
// renders each frame as two half passes that replay the neighbouring frames'
// random numbers, plus motion fields where a frame pair changes; stage 2
// forms the temporal gradients and reconstructs the shot in sliding windows
// (core/temporal/temporal_window.h), which own the schedule of what each
// frame needs.
#pragma once

#include <climits>
#include <memory>

#include "core/gradient/gradient_film.h"
#include "core/job/integrators/integrator_runner.h"
#include "core/temporal/temporal_window.h"
#include "core/temporal/tgpt_settings.h"

namespace gdvr {

class TgptRunner final : public IntegratorRunner {
 public:
  // The job's shifts and reconstruction as T-GPT settings, checked.
  static Expected<std::unique_ptr<TgptRunner>> create(const JobSpec& job, std::vector<int> job_frames);

  Status render(const FrameRenderContext& context, int frame, FrameBuffers* out) override;
  std::vector<int> frames_needed(int frame) const override { return windows_.frames_needed(frame); }
  Expected<FrameOutput> finalize(int frame, const std::map<int, FrameBuffers>& buffers) override;
  bool buffers_needed(int frame, int next_out) const override { return windows_.buffers_needed(frame, next_out); }
  int windows_solved() const override { return windows_.windows_solved(); }
  double finalize_seconds_prior(const FrameRenderSettings& settings, int frames) const override;
  bool reads_spilled_buffers() const override { return true; }
  // The first call times a two-frame window solve of the frame's buffers and
  // tells the budget what the shot's window solves will cost per frame.
  void calibrate_stage2(const LayeredImage& layers, FrameTimeBudget* budget) override;
  Expected<TileGrid> tile_grid(int width, int height) const override { return windows_.tile_grid(width, height); }
  Expected<Image> reconstruct_tiles(int frame, const std::vector<int>& tiles,
                                    const std::map<int, FrameBuffers>& buffers) override;
  Expected<FrameOutput> finalize_solved(int frame, const std::map<int, FrameBuffers>& buffers, Image solved) override;

 private:
  TgptRunner(TgptSettings settings, bool clamp_negative, std::vector<int> job_frames);
  // `solved`: the reconstructed image when given (tiles solved elsewhere), else solved here.
  Expected<FrameOutput> finalize_output(int frame, const std::map<int, FrameBuffers>& buffers, Image* solved);
  // Window frames solved per frame of the shot: each frame lies in about
  // W/H windows (2 at the default overlap), fewer near the shot's ends.
  double window_frames_per_frame() const;
  const TgptSettings settings_;
  const bool clamp_negative_;
  TemporalWindowCache windows_;  // the job's frames, and stage 2's solved windows

  // ---- Stage 1, across the frames of one process ----
  std::unique_ptr<FrameScene> scene_prev_, scene_next_;  // temporal_shift reconnect: the neighbours' scenes
  // Pass B of the last frame rendered: its frame and count (pass A of the
  // next frame takes that count), and its buffers where the pair towards the
  // next frame is static (the next pass A is then a copy).
  int last_b_frame_ = INT_MIN;
  int last_b_spp_ = 0;
  bool last_b_kept_ = false;
  GradientFilmBuffers last_b_;
  bool solve_calibrated_ = false;
};

}  // namespace gdvr
