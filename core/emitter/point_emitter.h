// Point and spot lights: a delta position with intensity (W/sr), the spot's
// falling off linearly in angle between beam_width and cutoff_angle
// (Mitsuba's spot). Never hit by a ray; reached by next-event estimation only.
#pragma once

#include "core/emitter/emitter.h"
#include "core/emitter/emitter_sample.h"

namespace gdvr {

// The direction from `ref_p` to the light. `es` arrives with its emitter
// index set; `select_pdf` is the emitter selection's.
EmitterSample sample_point_emitter(const Emitter& em, Vec3f ref_p, float select_pdf, EmitterSample es);

}  // namespace gdvr
