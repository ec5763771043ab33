#include "core/gradient/replay_shift.h"

namespace gdvr {

ShiftResult replay_shift(const FrameScene& scene, const PathTracerSettings& path, const PathRecord& base,
                         const Ray& offset_ray, Sampler sampler_after_camera, PathCounters& counters) {
  ShiftResult r;
  PathSample offset = trace_path(scene, path, offset_ray, sampler_after_camera, counters);
  // Ratio 1 in primary sample space: w = 1/2 for both generations.
  constexpr float kW = 0.5f;
  Rgb offset_indirect = offset.radiance - offset.direct;
  r.offset_primal = offset_indirect * kW;
  r.base_weighted = base.indirect * kW;
  r.gradient = (offset_indirect - base.indirect) * kW;
  return r;
}

}  // namespace gdvr
