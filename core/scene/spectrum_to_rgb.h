// Spectra in Mitsuba scene files (`<spectrum value="..."/>`, wavelength:value
// lists, .spd files) turned into the linear sRGB values gdvr renders with,
// as Mitsuba 3 does in its RGB variants (so that gdvr and Mitsuba's
// scalar_rgb render the same file alike):
//  - a constant v is v in every channel, except inside an <emitter>, where it
//    stands for an equal-energy spectrum: CIE XYZ (v, v, v), which is not
//    white in sRGB (D65 white) but v * (1.2048, 0.9483, 0.9089);
//  - a list is integrated against the CIE 1931 colour-matching functions
//    (piecewise linear between its wavelengths, zero outside them) and
//    converted from XYZ to linear sRGB: an emitter's as radiance (normalised
//    so that an equal-energy spectrum of 1 has Y = 1), anything else as a
//    reflectance seen under D65 (a flat spectrum of 1 gives white, 1), clamped
//    to [0, 1] unless the quantity is unbounded (eta, k, int_ior, ext_ior).
#pragma once

#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/util/status.h"

namespace gdvr {

enum class SpectrumRole {
  kEmission,     // inside <emitter>: radiance, intensity, irradiance
  kReflectance,  // bounded to [0, 1]
  kUnbounded,    // eta, k, int_ior, ext_ior: reflectance-style, only negatives clamped
};

// The role of parameter `name` of a plugin, inside an emitter or not.
SpectrumRole spectrum_role(const std::string& name, bool within_emitter);

Rgb constant_spectrum_to_rgb(float value, SpectrumRole role);

// `wavelengths` in nanometres, strictly increasing, at least two; values at
// those wavelengths. Fails naming the problem otherwise.
Expected<Rgb> spectrum_list_to_rgb(const std::vector<double>& wavelengths, const std::vector<double>& values,
                                   SpectrumRole role);

// Parses a Mitsuba .spd file: one "wavelength value" pair per line, '#'
// starts a comment. `name` is used in messages.
Status parse_spd(const std::string& text, const std::string& name, std::vector<double>* wavelengths,
                 std::vector<double>* values);

}  // namespace gdvr
