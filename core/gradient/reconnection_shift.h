// Shifts built from the cached base path (Kettunen et al. 2015; docs/gpt.md,
// "Shift mappings"):
// - reconnection with half-vector copy: glossy/specular base vertices are
//   followed by half-vector copy (Dirac lobes by the same lobe), and the
//   offset reconnects to x_{k+1} once x_k, its offset vertex and x_{k+1} are
//   all diffuse. Offset states: not reconnected / just reconnected (x_{k+1}
//   shared, BSDF there re-evaluated for the new incoming direction) /
//   reconnected (the rest of the base path reused, same f and pdfs).
// - hybrid: like the above, but vertices before the reconnection are
//   replayed (the base's random numbers sample the offset's BSDF; ratio 1).
// Emitter sampling reuses the base's light sample (its random numbers: for
// area-uniform triangle sampling the same light point, the Jacobian
// (cos'_L d²)/(cos_L d'²) then being folded into the offset's Le/pdf).
// Every branch checks that the reverse shift would take the same branch.
#pragma once

#include "core/gradient/camera_hit.h"
#include "core/gradient/gpt_settings.h"
#include "core/gradient/shift_mapping.h"
#include "core/render/path_tracer.h"

namespace gdvr {

// `replay_prefix` = false: reconnection shift; true: hybrid shift.
// `offset_first`: the base's camera ray moved by one pixel (same sub-pixel
// position) and its traced first hit.
ShiftResult shift_from_cache(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                             const CameraHit& offset_first, bool replay_prefix, PathCounters& counters,
                             ShiftTrace* trace = nullptr);

// The same, tracing the offset's camera ray itself.
inline ShiftResult shift_from_cache(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                                    const Ray& offset_ray, bool replay_prefix, PathCounters& counters,
                                    ShiftTrace* trace = nullptr) {
  return shift_from_cache(scene, settings, base, trace_camera_hit(scene, offset_ray, counters), replay_prefix,
                          counters, trace);
}

inline ShiftResult reconnection_shift(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                                      const Ray& offset_ray, PathCounters& counters, ShiftTrace* trace = nullptr) {
  return shift_from_cache(scene, settings, base, offset_ray, /* replay_prefix = */ false, counters, trace);
}

}  // namespace gdvr
