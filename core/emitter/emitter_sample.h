// What sampling an emitter towards a reference point gives the integrators.
#pragma once

#include "core/math/vec.h"

namespace gdvr {

// A sampled direction towards an emitter, as Mitsuba's DirectionSample.
struct EmitterSample {
  Vec3f d;               // unit direction from the reference point
  float dist = 0;        // to the emitter point (infinity for infinite emitters)
  float pdf = 0;         // solid angle, including emitter selection (1 for deltas: see `delta`)
  bool delta = false;
  Rgb weight;            // Le / pdf (already divided; zero when it does not emit towards us)
  int emitter = -1;
};

}  // namespace gdvr
