// Directional light: irradiance arriving from one direction (the emitter's
// to_world maps +z to the direction light travels). A delta direction at
// infinity; reached by next-event estimation only.
#pragma once

#include "core/emitter/emitter.h"
#include "core/emitter/emitter_sample.h"

namespace gdvr {

// `es` arrives with its emitter index set; `select_pdf` is the emitter selection's.
EmitterSample sample_directional_emitter(const Emitter& em, float select_pdf, EmitterSample es);

}  // namespace gdvr
