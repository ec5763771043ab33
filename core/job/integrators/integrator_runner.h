// One integrator as a job runs it (core/job/job_runner.h), in the two stages
// a render farm may run in separate processes:
//   1. render: a frame to its buffers, every layer the integrator produces
//      before reconstruction;
//   2. finalize: buffers to the final frame (reconstruction, direct light added).
// Each integrator implements it in its own file of this folder; the job
// runner, the farm and the server see only this interface, so adding an
// integrator touches this folder only.
#pragma once

#include <climits>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/job/frame_output.h"
#include "core/job/frame_time_budget.h"
#include "core/job/job_spec.h"
#include "core/recon/tile_grid.h"
#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"
#include "core/scene/scene.h"
#include "core/util/status.h"

namespace gdvr {

// What stage 1 of one frame works with; the job runner has moved the scene to
// the frame's time.
struct FrameRenderContext {
  const FrameScene& scene;
  const Scene& description;  // the scene description at the frame's time
  const FrameRenderSettings& settings;
  const std::vector<bool>& animated_shapes;  // by shape index
  // The description at another frame's time, from `description` (T-GPT's
  // neighbours).
  std::function<Status(int frame, Scene* description)> describe_frame;
  const FrameRenderControl& control;
  // The job's time budget (null: none): the frame's allowance, and where the
  // integrator records what its sampling cost (core/job/frame_time_budget.h).
  FrameTimeBudget* budget = nullptr;
};

class IntegratorRunner {
 public:
  virtual ~IntegratorRunner() = default;

  // ---- Stage 1 ----
  // `frame`'s buffers into out->layers, and into out->stats what this
  // integrator measured (render_seconds, spp, rays, temporal_rays) and left out.
  virtual Status render(const FrameRenderContext& context, int frame, FrameBuffers* out) = 0;
  // `frame`'s stage-1 layers are complete: the integrator's, the feature
  // buffers and a denoised data term, all that its finalize will read. Under
  // a time budget that pays stage 2, a runner whose stage 2 the budget cannot
  // measure before the shot's end times a sample of it here (T-GPT's window
  // solve), on the buffers it will really solve.
  virtual void calibrate_stage2(const LayeredImage& /*layers*/, FrameTimeBudget* /*budget*/) {}

  // ---- Stage 2 ----
  // The frames whose buffers finalizing `frame` reads, ascending.
  virtual std::vector<int> frames_needed(int frame) const { return {frame}; }
  // `buffers` must hold frames_needed(frame). Frames finalized in increasing
  // order share the work they have in common (T-GPT's windows are solved once).
  virtual Expected<FrameOutput> finalize(int frame, const std::map<int, FrameBuffers>& buffers) = 0;
  // Whether a streaming run must keep the buffers of `frame` it holds once
  // every frame before `next_out` is final (next_out = INT_MAX: all are).
  virtual bool buffers_needed(int frame, int next_out) const { return frame >= next_out; }
  // Reconstruction windows solved so far (0 for an integrator without them).
  virtual int windows_solved() const { return 0; }
  // Stage 2's expected seconds per frame of a `frames`-frame job at these
  // settings, before any frame was finalized: what a time budget reserves for
  // it until measured (core/job/frame_time_budget.h). pt and gpt finalize
  // each frame right after rendering it, so the budget measures theirs at once.
  virtual double finalize_seconds_prior(const FrameRenderSettings& /*settings*/, int /*frames*/) const { return 0; }
  // Whether finalize reads FrameBuffers::on_disk (run_job's memory limit).
  virtual bool reads_spilled_buffers() const { return false; }

  // ---- Stage 2 by tiles (a farm's tiled finalize, docs/farm.md) ----
  // Only integrators with a window solve split it; the others refuse.
  // The tile grid of the reconstruction for frames of width × height.
  virtual Expected<TileGrid> tile_grid(int /*width*/, int /*height*/) const { return no_tiled_finalize(); }
  // The reconstructed image of `frame` before the direct light, with only the
  // cores of `tiles` solved (0 elsewhere); `buffers` as for finalize.
  virtual Expected<Image> reconstruct_tiles(int /*frame*/, const std::vector<int>& /*tiles*/,
                                            const std::map<int, FrameBuffers>& /*buffers*/) {
    return no_tiled_finalize();
  }
  // finalize with the reconstructed image given (every tile's part pasted
  // together); `buffers` need only hold the frame and the next one.
  virtual Expected<FrameOutput> finalize_solved(int /*frame*/, const std::map<int, FrameBuffers>& /*buffers*/,
                                                Image /*solved*/) {
    return no_tiled_finalize();
  }

 protected:
  static Status no_tiled_finalize() {
    return unimplemented("this integrator's finalize does not split into tiles (only tgpt's does)");
  }
};

// The job's integrator, its settings built from the job and checked (errors
// name the job's field). `job_frames`: the job's frame range, ascending.
Expected<std::unique_ptr<IntegratorRunner>> make_integrator_runner(const JobSpec& job, std::vector<int> job_frames);

// The statistics every integrator's frame result carries (seconds, spp, rays,
// invalid_samples), with the dropped samples said in left_out as `dropped`.
template <typename FrameResult>
void record_render_stats(const FrameResult& r, const char* dropped, FrameStats* stats) {
  stats->render_seconds = r.seconds;
  stats->sampling_seconds = r.sampling_seconds;
  stats->spp = r.spp;
  stats->rays = r.rays;
  if (r.invalid_samples > 0) stats->left_out.push_back(std::to_string(r.invalid_samples) + " " + dropped);
}

}  // namespace gdvr
