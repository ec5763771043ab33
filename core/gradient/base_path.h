// Traces and records the base path of G-PT. The estimator and the order in
// which random numbers are drawn are exactly those of trace_path() (Mitsuba 3's
// `path`: max_depth, Russian roulette from rr_depth, power-heuristic MIS of
// emitter and BSDF sampling), so the base estimate equals the PT image for the
// same seed and G-PT converges to the same image as PT.
#pragma once

#include "core/gradient/camera_hit.h"
#include "core/gradient/path_record.h"
#include "core/math/rng.h"
#include "core/render/path_tracer.h"

namespace gdvr {

// Fills `record` (cleared first; its vertex storage is reused between calls).
// `first`: the camera ray and its traced first hit; `sampler` is positioned
// after the camera's sub-pixel sample.
void trace_base_path(const FrameScene& scene, const PathTracerSettings& settings, const CameraHit& first,
                     Sampler& sampler, PathCounters& counters, PathRecord* record);

// Sets every vertex's PathVertex::dark_suffix from the record's contributions
// (trace_base_path calls it; tests call it after editing a record).
void mark_dark_suffixes(PathRecord* record);

// The same, tracing the camera ray itself.
inline void trace_base_path(const FrameScene& scene, const PathTracerSettings& settings, const Ray& camera_ray,
                            Sampler& sampler, PathCounters& counters, PathRecord* record) {
  trace_base_path(scene, settings, trace_camera_hit(scene, camera_ray, counters), sampler, counters, record);
}

}  // namespace gdvr
