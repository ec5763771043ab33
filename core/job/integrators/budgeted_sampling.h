// How a single-pass integrator (pt, gpt) samples a frame under the job's time
// budget (core/job/frame_time_budget.h): the first frame a process renders
// runs passes of the job's pass size against the clock, which measures the
// cost of a sample; every later frame renders the count that fits its
// allowance at that cost, in one go. T-GPT, whose passes must pair across
// frames, picks its counts itself (tgpt_runner.cpp).
#pragma once

#include "core/job/integrators/integrator_runner.h"

namespace gdvr {

// The frame's render settings: the job's, or under a budget either a deadline
// (time_budget_s, no cost measured yet) or a count (spp, a multiple of the
// job's pass size).
FrameRenderSettings budgeted_render_settings(const FrameRenderContext& context);

// Tells the budget what the frame's sampling cost (nothing without one).
void record_budgeted_sampling(const FrameRenderContext& context, int spp, double sampling_seconds);

}  // namespace gdvr
