// Hybrid shift (docs/gpt.md, "Shift mappings"): random replay of the base's
// random numbers until the first diffuse-diffuse pair, then reconnection
// (Kettunen et al. 2015), with the balance-heuristic MIS of the pair
// (replayed vertices contribute a ratio of 1).
#pragma once

#include "core/gradient/reconnection_shift.h"

namespace gdvr {

inline ShiftResult hybrid_shift(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                                const Ray& offset_ray, PathCounters& counters, ShiftTrace* trace = nullptr) {
  return shift_from_cache(scene, settings, base, offset_ray, /* replay_prefix = */ true, counters, trace);
}

}  // namespace gdvr
