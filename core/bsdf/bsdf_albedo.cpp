#include "core/bsdf/bsdf_albedo.h"

#include <algorithm>

#include "core/bsdf/fresnel.h"

namespace gdvr {
namespace {

Rgb clamp01(Rgb c) {
  // std::clamp keeps NaN; a NaN texel must not reach the denoiser.
  auto unit = [](float v) { return v > 0.0f ? std::min(v, 1.0f) : 0.0f; };
  return {unit(c.r), unit(c.g), unit(c.b)};
}

}  // namespace

Rgb bsdf_albedo(const Bsdf& bsdf, Vec2f uv) {
  switch (bsdf.type) {
    case BsdfType::kDiffuse:
    case BsdfType::kPlastic:
    case BsdfType::kRoughPlastic:
      return clamp01(bsdf.reflectance.eval(uv));
    case BsdfType::kConductor:
    case BsdfType::kRoughConductor:
      return clamp01(fresnel_conductor(1.0f, bsdf.eta, bsdf.k) * bsdf.specular_reflectance.eval(uv));
    case BsdfType::kDielectric:
    case BsdfType::kThinDielectric:
    case BsdfType::kRoughDielectric:
      return clamp01(bsdf.specular_transmittance.eval(uv));
  }
  return Rgb(1.0f);
}

}  // namespace gdvr
