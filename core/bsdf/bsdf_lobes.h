// Per-type BSDF kernels behind the switch dispatch in bsdf.cpp. Internal to
// core/bsdf. All work in the front-side frame (two_sided is resolved by the
// dispatcher). wo is the fixed direction (Mitsuba's si.wi), wi the sampled or
// evaluated one (Mitsuba's wo); both point away from the surface.
#pragma once

#include "core/bsdf/bsdf.h"

namespace gdvr {
namespace lobes {

BsdfEval diffuse_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi);
bool diffuse_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);

bool conductor_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);
BsdfEval rough_conductor_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi);
bool rough_conductor_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);
// The rough BSDFs' samples split at their Beckmann slope inversion (bsdf.h).
bool rough_conductor_start_slope_inversion(const Bsdf& b, Vec3f wo, Vec2f u, BeckmannSlopeInversion* inv);
bool rough_conductor_sample_from_slope(const Bsdf& b, Vec2f uv, Vec3f wo, Vec2f slope11, BsdfSample* s);

BsdfEval plastic_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi);
bool plastic_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);
BsdfEval rough_plastic_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi);
bool rough_plastic_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);
bool rough_plastic_start_slope_inversion(const Bsdf& b, Vec3f wo, float u_lobe, Vec2f u, BeckmannSlopeInversion* inv);
bool rough_plastic_sample_from_slope(const Bsdf& b, Vec2f uv, Vec3f wo, Vec2f slope11, BsdfSample* s);
void rough_plastic_precompute(Bsdf* b);

bool dielectric_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);
BsdfEval rough_dielectric_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi);
bool rough_dielectric_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);
bool rough_dielectric_start_slope_inversion(const Bsdf& b, Vec3f wo, Vec2f u, BeckmannSlopeInversion* inv);
bool rough_dielectric_sample_from_slope(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f slope11,
                                        BsdfSample* s);
bool thin_dielectric_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s);

}  // namespace lobes
}  // namespace gdvr
