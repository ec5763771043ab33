// Named indices of refraction accepted wherever Mitsuba takes `int_ior` /
// `ext_ior` as a string ("bk7", "water", "air", ...). Values from Mitsuba's
// table (sodium D line, 589 nm).
#pragma once

#include <string>

namespace gdvr {

// Returns false for an unknown name. Case-sensitive like Mitsuba.
bool lookup_ior(const std::string& name, float* ior);

}  // namespace gdvr
