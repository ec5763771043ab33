// What a job's stages hand on for each frame: the buffers of stage 1 (render)
// and the final frame of stage 2 (finalize), each with its statistics.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/image/layer_region_source.h"

namespace gdvr {

struct FrameStats {
  int frame = 0;
  double render_seconds = 0;
  // Of render_seconds, the sampling passes: what a time budget scales (the
  // direct-light pass, motion vectors and resolves are fixed costs).
  double sampling_seconds = 0;
  // The frame's stage 2: its reconstruction (G-PT), or the window solves
  // finalizing it ran (T-GPT: a window is solved while finalizing the first
  // frame that needs it, so the shot's solves add up over its frames).
  double reconstruct_seconds = 0;
  // The feature buffers (albedo, N, Z; core/render/feature_buffers.h): a fixed
  // cost beside render_seconds, inside the time budget; 0 when the job's
  // outputs.exr_layers selects none of them (they are not rendered then).
  double feature_seconds = 0;
  // Stage 1 on the job runner's clock: render_seconds + feature_seconds + the
  // runner's own work for the frame (moving the scene). With
  // reconstruct_seconds and what the caller does with the final frame, the
  // frame's share of a time budget (core/job/frame_time_budget.h).
  double stage1_seconds = 0;
  int spp = 0;
  // T-GPT: the samples per pixel of pass A and pass B (spp is their sum).
  // Pass A of frame t+1 has the count of pass B of frame t (they replay the
  // same random numbers), with or without a time budget; 0 for pt and gpt.
  int pass_a_spp = 0, pass_b_spp = 0;
  uint64_t samples = 0;        // camera samples
  uint64_t rays = 0;           // every ray traced (closest hit and shadow)
  // Rays whose results enter a non-zero temporal gradient (tgpt): motion
  // vectors and temporal offsets. 0 for pt, gpt and static frame pairs.
  uint64_t temporal_rays = 0;
  double samples_per_second = 0;
  double rays_per_second = 0;
  std::vector<std::string> left_out;  // what the pipeline skipped, and why
  // Filled by the output stage (core/job/job_outputs.h):
  double rel_mse = -1;             // per-pixel relMSE against the job's reference; -1: none
  double rel_mse_global = -1;      // global relMSE against it; -1: none
  double shift_failure_rate = -1;  // mean of the shift_failure_rate layer; -1: not gradient-domain
};

// Stage 1: every layer the integrator produces before reconstruction (pt: the
// image; gpt: primal, dx, dy, ...), and the render statistics.
struct FrameBuffers {
  int frame = 0;
  LayeredImage layers;
  FrameStats stats;  // render-stage statistics; finalize adds its own
  // Set when the layers are on disk instead: spilled by run_job under its
  // memory limit (JobRunOptions::memory_limit_bytes), or left in their EXR by
  // a farm tile task (core/farm/buffer_store.h). `layers` is then empty, and
  // an integrator that reads buffers by region (tgpt) reads them from here.
  std::shared_ptr<const LayerRegionSource> on_disk;
};

// Stage 2: the final frame.
struct FrameOutput {
  int frame = 0;
  LayeredImage image;  // unnamed layer = the final RGB image
  FrameStats stats;
};

}  // namespace gdvr
