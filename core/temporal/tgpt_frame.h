// Stage 1 of T-GPT for one frame (Manzi et al. 2016; docs/tgpt.md): two half-spp G-PT passes
// with the streams of core/temporal/pass_schedule.h, and the motion fields
// towards the neighbouring frames where the frame pair changes. Everything
// stage 2 needs (the temporal gradients are differences between this frame's
// pass B and the next frame's pass A) is in the returned buffers, so a farm can
// render frames in separate processes. With motion compensation
// (TgptSettings::motion_compensation) pass A replays pass B of the previous
// frame along the backward motion field (core/temporal/replay_map.h).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/gradient/gpt_integrator.h"
#include "core/render/frame_scene.h"
#include "core/temporal/change_detection.h"
#include "core/temporal/motion_vectors.h"
#include "core/temporal/pass_schedule.h"
#include "core/temporal/tgpt_settings.h"

namespace gdvr {

// The frame's animated description and its neighbours in the job (null at the
// shot's ends), with what changes towards each.
struct TgptNeighbourhood {
  const Scene* at_t = nullptr;
  const Scene* prev = nullptr;
  const Scene* next = nullptr;
  FramePairChanges to_prev, to_next;  // detect_changes(prev, t), detect_changes(t, next)
  // The neighbours as renderable scenes (their accelerators at their times):
  // needed by temporal_shift = reconnect where the pair changes.
  const FrameScene* prev_scene = nullptr;
  const FrameScene* next_scene = nullptr;
};

// How many samples each half pass takes. Left default, both take
// tgpt_pass_spp(render.spp). Under a time budget (core/job/frame_time_budget.h)
// pass A takes the count of the previous frame's pass B, with which it
// replays the same random numbers (dt = A_{t+1} − B_t is a correlated
// difference only at equal counts), and pass B the count the budget picks
// once pass A is measured.
struct TgptPassSizes {
  int a_spp = 0;  // > 0: pass A's count
  // a_spp == 0 and a_seconds > 0: pass A renders passes of tgpt_pass_spp(render.spp)
  // until about this many seconds are spent (the first frame a process
  // renders under a budget: nothing to pair with, no cost measured yet).
  double a_seconds = 0;
  // Pass B's count, given pass A's spp and seconds (both 0 when A was
  // copied from the previous frame); empty: as pass A.
  std::function<int(int a_spp, double a_seconds)> b_spp;
};

struct TgptFrameRender {
  GradientFilmBuffers a, b;  // the two half passes
  // Emitters seen directly, from one stratified pass for the frame
  // (gpt.direct_strata > 0); empty: the passes' own `direct` is averaged.
  Image direct;
  MotionField forward;       // towards the next frame; empty when the pair is static or at the shot's end
  MotionField backward;      // towards the previous frame; likewise
  int spp = 0;               // both passes together
  int a_spp = 0, b_spp = 0;  // each pass (a copied pass A counts its spp)
  double sampling_seconds = 0;  // the passes' wall time (no direct light, no motion vectors)
  uint64_t rays = 0;         // every ray this call traced (passes and motion vectors)
  // Rays whose results enter a non-zero temporal gradient: the motion-vector
  // rays, plus (replay) pass A's rays when the pair (prev, t) changes (pass A
  // is the replayed offset of the previous frame's dt) or (reconnect) the
  // temporal shifts' rays. A static shot counts zero.
  uint64_t temporal_rays = 0;
  uint64_t invalid_samples = 0;
  bool reused_pass_a = false;  // pass A taken from the previous frame's pass B (static pair)
  double seconds = 0;
  std::vector<std::string> left_out;  // what was skipped, and why
};

// Renders frame t of a shot. `reuse_a`, when non-null, must be pass B of the
// previous frame and the pair (prev, t) must be static: then it equals pass A
// of t sample for sample (same stream, same scene) and is copied instead of
// rendered; `sizes.a_spp` must then be the count it was rendered with. render.time_budget_s is not
// read: a budget reaches the passes as counts (`sizes`).
Expected<TgptFrameRender> render_tgpt_frame(const FrameScene& scene, const FrameRenderSettings& render,
                                            const TgptSettings& settings, TgptPassStreams streams,
                                            const TgptNeighbourhood& nb, const GradientFilmBuffers* reuse_a,
                                            const FrameRenderControl& control, const TgptPassSizes& sizes = {});

}  // namespace gdvr
