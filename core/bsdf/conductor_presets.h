// Named conductor materials (Mitsuba's `material` parameter: "Au", "Cu", ...),
// as RGB complex index of refraction.
#pragma once

#include <string>

#include "core/math/vec.h"

namespace gdvr {

// Returns false for an unknown name. "none" is the perfect mirror (eta 0, k 1).
bool lookup_conductor(const std::string& name, Rgb* eta, Rgb* k);

}  // namespace gdvr
