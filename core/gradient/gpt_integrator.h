// The frame integrator of G-PT, analogous to render_frame_pt: tiles on a TBB
// arena, spp or wall-time budget in passes, progress, cancel (checked per
// tile). Produces the gradient film's named buffers; reconstruction is a
// separate pure function (core/recon).
#pragma once

#include "core/gradient/gpt_settings.h"
#include "core/gradient/gradient_film.h"
#include "core/gradient/temporal_reconnection_shift.h"
#include "core/render/pt_integrator.h"

namespace gdvr {

struct ReplayMap;  // core/temporal/replay_map.h

struct GptFrameResult {
  GradientFilmBuffers buffers;
  int spp = 0;
  uint64_t rays = 0;
  uint64_t invalid_samples = 0;  // non-finite base paths or gradients dropped
  double shift_failure_rate = 0; // over all attempted offsets
  uint64_t temporal_rays = 0;    // rays of the temporal shifts (part of `rays`)
  double seconds = 0;
  double sampling_seconds = 0;   // of which the sampling passes (not the direct-light pass, not the resolve)
};

// `temporal`, when given, also shifts every base path into that frame
// (T-GPT's path-space temporal shift): buffers.temporal etc. are then filled.
// `replay`, when given (width × height), says whose sample stream each pixel
// replays and how it rotates its sub-pixel position (T-GPT's
// motion-compensated replay, GradientTracer::set_replay_map); without it the
// frame is the same bit for bit as before the map existed.
Expected<GptFrameResult> render_frame_gpt(const FrameScene& scene, const FrameRenderSettings& settings,
                                          const GptSettings& gpt, uint32_t frame, const FrameRenderControl& control,
                                          const TemporalShiftTarget* temporal = nullptr,
                                          const ReplayMap* replay = nullptr);

}  // namespace gdvr
