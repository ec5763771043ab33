// Random replay in primary sample space (Kelemen et al. 2002's space of random
// numbers; docs/gpt.md, "Shift mappings"): the offset is the
// path tracer run again in the neighbouring pixel with the base sample's own
// random numbers. The shift has Jacobian 1 in primary sample space, so both
// generations of a pair have the same density, the MIS weights are 1/2, and
// no shift ever fails. The simplest correct shift: the test oracle.
#pragma once

#include "core/gradient/shift_mapping.h"
#include "core/math/rng.h"
#include "core/render/path_tracer.h"

namespace gdvr {

// `sampler_after_camera`: the base's sampler as it was right after the camera
// sample was drawn (a copy; it is advanced here).
ShiftResult replay_shift(const FrameScene& scene, const PathTracerSettings& path, const PathRecord& base,
                         const Ray& offset_ray, Sampler sampler_after_camera, PathCounters& counters);

}  // namespace gdvr
