// Runs a whole job in-process: loads the scene, renders each frame of the
// range with the chosen integrator, reconstructs where the integrator needs it,
// and hands every final frame to the caller in order. Used by gdvr-render, the
// server and the farm workers alike.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/job/frame_output.h"
#include "core/job/frame_denoiser.h"
#include "core/job/job_spec.h"
#include "core/recon/tile_grid.h"
#include "core/util/status.h"

namespace gdvr {

struct JobProgress {
  int frames_done = 0;
  int frames_total = 0;
  double fraction = 0;         // of the whole job, including the frame in flight
  double eta_seconds = -1;     // -1 until it can be estimated
};

struct JobRunOptions {
  int threads = 0;               // 0: all cores
  std::string base_dir;          // relative scene paths resolve here
  std::string asset_root;        // when set, scene files must lie inside it
  std::vector<int> skip_frames;  // already final (resume): not rendered again
  // Seconds the caller spends on each final frame beyond writing it (the
  // report's denoiser), which a time budget must pay for as well: run_job
  // measures what on_frame_final takes, and this is its guess until then.
  double caller_seconds_per_frame = 0;
  // The buffered frames a streaming stage 2 holds (tgpt's windows) stay in
  // memory up to this many bytes of pixels; beyond it a frame's buffers go to
  // an unnamed file in spill_dir (empty: the system's temporary folder) and
  // the window solve reads each tile's region from there (docs/tgpt.md,
  // "Memory"). < 0: no limit. Integrators that hold no frames ignore it.
  long long memory_limit_bytes = -1;
  std::string spill_dir;
  // The process's denoiser, if it has one (core/job/frame_denoiser.h): T-GPT's
  // denoised data term needs it (reconstruction.data_term).
  FrameDenoiser denoiser;
};

struct JobCallbacks {
  std::function<void(const FrameOutput&)> on_frame_final;  // in frame order
  std::function<void(const JobProgress&)> on_progress;
  // Optional, for a time budget: the seconds on_frame_final will take per
  // frame, estimated on a rendered frame's buffers (gdvr-render times writing
  // them). Called once, when the first frame rendered cannot be finalized at
  // once (T-GPT waits for its window), so that the output of a window's frames
  // is reserved from the frames before it; where frames come out at once,
  // their output is measured instead.
  std::function<double(const FrameBuffers&)> estimate_frame_final_seconds;
};

// Returns kCancelled if *cancel became true (checked once per tile).
Status run_job(const JobSpec& job, const JobRunOptions& options, const JobCallbacks& callbacks,
               const std::atomic<bool>* cancel);

// Validates a job without rendering: its values (validate in
// core/job/job_validation.h), the integrator's settings, and the scene with
// the job's params and tracks.
Status validate_job(const JobSpec& job, const JobRunOptions& options);

// What a job will render once the scene file and the job's <default>
// overrides (params) are resolved: the values a resource limit must apply to,
// since a job that leaves width unset renders the scene's film width, which
// `params: {"res": "4096"}` may have set. Each comes with where it came from
// ("the job's width", "params.res (scene.xml:12)", "the scene (scene.xml:9)"),
// for a refusal that names its cause.
struct ResolvedSetting {
  long long value = 0;
  std::string origin;
};
struct ResolvedRender {
  ResolvedSetting width, height;
  // Samples per pixel per frame; with a time budget and no spp, the 1-spp
  // pass size (the budget, not spp, then bounds the work).
  ResolvedSetting spp;
  double time_budget_s = 0;  // per frame; 0: none
  int frames = 0;
};
// Loads the scene as validate_job does (same errors) and resolves the above.
Expected<ResolvedRender> resolve_job(const JobSpec& job, const JobRunOptions& options);

// ---- Staged execution ----
// A job runs in two stages, which a render farm can run as separate commands on
// separate machines (run_job chains them in one process, so both give the same
// frames):
//   1. render: each frame to its sample buffers, every layer the integrator
//      produces before reconstruction (pt: the image; gpt: primal, dx, dy, ...);
//   2. finalize: buffers -> the final frame (reconstruction, direct light added).

// Renders `frames` (a subset of the job's frames, in any order) and hands each
// frame's buffers to `on_buffers`; a non-ok Status from it stops the run.
Status render_job_buffers(const JobSpec& job, const JobRunOptions& options, const std::vector<int>& frames,
                          const std::function<Status(FrameBuffers&&)>& on_buffers,
                          const std::function<void(const JobProgress&)>& on_progress,
                          const std::atomic<bool>* cancel);

// The frames whose buffers finalizing `frame` reads (its reconstruction
// window), given all frames of the job.
std::vector<int> frames_needed_to_finalize(const JobSpec& job, const std::vector<int>& job_frames, int frame);

// Stage 2 for one frame. `buffers` must hold frames_needed_to_finalize(frame).
Expected<FrameOutput> finalize_frame(const JobSpec& job, int frame, const std::map<int, FrameBuffers>& buffers);

class IntegratorRunner;

// Stage 2 for several frames of one job in one process (a farm's finalize
// task): each output is finalize_frame's, bit for bit, but what neighbouring
// frames share is kept between calls. A T-GPT frame is the blend of the
// windows containing it, and finalize_frame solves them all for its one
// frame, so a shot finalized frame by frame solves each window once for every
// frame it holds (W times); a finalizer solves each once, as the in-process
// run does, when its frames come in increasing order (and again, still
// correctly, when an earlier frame comes after its windows were let go).
class JobFinalizer {
 public:
  static Expected<std::unique_ptr<JobFinalizer>> create(const JobSpec& job);
  ~JobFinalizer();
  JobFinalizer(const JobFinalizer&) = delete;
  JobFinalizer& operator=(const JobFinalizer&) = delete;

  // The frames whose buffers finalizing `frame` reads.
  std::vector<int> frames_needed(int frame) const;
  // `buffers` must hold frames_needed(frame).
  Expected<FrameOutput> finalize(int frame, const std::map<int, FrameBuffers>& buffers);
  // Reconstruction windows solved so far (0 for pt and gpt, which have none).
  int windows_solved() const;

  // ---- By tiles (a farm's tiled finalize: docs/farm.md; tgpt only, the
  // others refuse with kUnimplemented) ----
  // The reconstruction's tile grid for frames of width × height.
  Expected<TileGrid> tile_grid(int width, int height) const;
  // `frame`'s reconstructed image before the direct light, only the cores of
  // `tiles` solved (0 elsewhere). Frames in increasing order share windows.
  Expected<Image> reconstruct_tiles(int frame, const std::vector<int>& tiles,
                                    const std::map<int, FrameBuffers>& buffers);
  // finalize with the reconstructed image given (all tiles' parts pasted):
  // the same frame as finalize, bit for bit; `buffers` need only the frame and the next.
  Expected<FrameOutput> finalize_solved(int frame, const std::map<int, FrameBuffers>& buffers, Image solved);

 private:
  explicit JobFinalizer(std::unique_ptr<IntegratorRunner> runner);
  std::unique_ptr<IntegratorRunner> runner_;
};

}  // namespace gdvr
