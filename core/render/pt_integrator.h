// The frame integrator for plain path tracing: tiles, sample budget (spp or
// wall time), statistics. Produces the final image plus diagnostic layers.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>

#include "core/image/image.h"
#include "core/render/frame_scene.h"
#include "core/render/direct_emission.h"
#include "core/render/path_batch.h"
#include "core/render/path_tracer.h"
#include "core/render/tile_scheduler.h"

namespace gdvr {

struct FrameRenderSettings {
  int width = 0, height = 0;
  int spp = 4;
  // > 0: render passes of `spp` until about this many seconds are spent (the
  // direct-light pass included). A job's time budget sets it only for the
  // first frame, before a cost per sample is measured; later frames get a
  // count (core/job/frame_time_budget.h).
  double time_budget_s = 0;
  uint64_t seed = 0;
  int threads = 0;
  int tile_size = 16;
  int paths_in_flight = kPathBatch;  // per thread (path_batch.h); 1: one at a time
  PathTracerSettings path;
  // Emitters seen directly from the camera: their own stratified pass, or
  // (strata 0) the paths' own camera samples. See direct_emission.h.
  DirectEmissionSettings direct = default_direct_emission(/*gradient_domain=*/false);
};

struct FrameRenderResult {
  Image color;         // mean radiance, 3 channels
  Image direct;        // emitters seen directly (part of color)
  Image variance;      // per-pixel variance of the mean, per channel
  int spp = 0;         // samples per pixel actually taken
  uint64_t rays = 0;
  uint64_t invalid_samples = 0;
  double seconds = 0;
  double sampling_seconds = 0;  // of which the sampling passes (not the direct-light pass, not the means)
};

struct FrameRenderControl {
  const std::atomic<bool>* cancel = nullptr;
  std::function<void(double fraction)> on_progress;
};

// The frame's direct-light pass (settings.direct, fixed jitter stream
// kDirectEmissionStream); an empty image and no rays when it is disabled.
// Every integrator runs it before its paths, so a time budget includes it.
Expected<DirectEmissionResult> render_frame_direct(const FrameScene& scene, const FrameRenderSettings& settings,
                                                   const FrameRenderControl& control);

// The tile options of one pass of an integrator's frame: the settings' threads
// and tile size, the control's cancel flag, and progress as the fraction of
// the pass (spp mode) or of the time budget spent since `frame_start`.
TileRunOptions pass_tile_options(const FrameRenderSettings& settings, const FrameRenderControl& control,
                                 std::chrono::steady_clock::time_point frame_start);

Expected<FrameRenderResult> render_frame_pt(const FrameScene& scene, const FrameRenderSettings& settings,
                                            uint32_t frame, const FrameRenderControl& control);

}  // namespace gdvr
