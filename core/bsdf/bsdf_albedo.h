// The colour of a surface independent of lighting and view, as a denoiser's
// albedo guide wants it (Intel Open Image Denoise, "Albedos"): not the
// directional albedo a furnace test measures, but a value in [0, 1] that
// changes where the material changes.
#pragma once

#include "core/bsdf/bsdf.h"

namespace gdvr {

// Per BSDF type:
//   diffuse:                the reflectance texture;
//   plastic (smooth/rough): the diffuse reflectance (a non-absorbing clear
//                           coat is ignored, as OIDN's docs allow);
//   rough conductor:        specular_reflectance times the Fresnel
//                           reflectance at normal incidence;
//   dielectrics:            the specular transmittance (1 for clear glass:
//                           OIDN's choice for glass it does not see through);
//   smooth conductor:       as the rough one.
// A feature pass follows smooth conductors and dielectrics (delta BSDFs) to
// what they show instead (feature_buffers.h), and asks here only where it
// gives up on such a chain.
// Clamped to [0, 1].
Rgb bsdf_albedo(const Bsdf& bsdf, Vec2f uv);

}  // namespace gdvr
