// Traces and records the base path of G-PT. The estimator and the order in
// which random numbers are drawn are exactly those of trace_path() (Mitsuba 3's
// `path`: max_depth, Russian roulette from rr_depth, power-heuristic MIS of
// emitter and BSDF sampling), so the base estimate equals the PT image for the
// same seed and G-PT converges to the same image as PT.
#pragma once

#include "core/gradient/path_record.h"
#include "core/math/rng.h"
#include "core/render/path_tracer.h"

namespace gdvr {

// Fills `record` (cleared first; its vertex storage is reused between calls).
void trace_base_path(const FrameScene& scene, const PathTracerSettings& settings, const Ray& camera_ray,
                     Sampler& sampler, PathCounters& counters, PathRecord* record);

}  // namespace gdvr
