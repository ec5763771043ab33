// Bsdf set-up and the switch dispatch over BsdfType. The per-type kernels live
// in diffuse.cpp, conductor.cpp, plastic.cpp and dielectric.cpp.
#include "core/bsdf/bsdf.h"

#include <limits>

#include "core/bsdf/bsdf_lobes.h"
#include "core/bsdf/fresnel.h"

namespace gdvr {
namespace {

// Mitsuba's scalar Texture::mean() in scalar_rgb: the channel average for
// constant colours (and the checkerboard's halves), mean luminance for bitmaps.
float texture_scalar_mean(const Texture& t) {
  if (t.type == TextureType::kBitmap) return luminance(t.mean());
  return average(t.mean());
}

uint32_t lobes_of(BsdfType type) {
  switch (type) {
    case BsdfType::kDiffuse: return kLobeDiffuseReflection;
    case BsdfType::kConductor: return kLobeDeltaReflection;
    case BsdfType::kRoughConductor: return kLobeGlossyReflection;
    case BsdfType::kPlastic: return kLobeDeltaReflection | kLobeDiffuseReflection;
    case BsdfType::kRoughPlastic: return kLobeGlossyReflection | kLobeDiffuseReflection;
    case BsdfType::kDielectric: return kLobeDeltaReflection | kLobeDeltaTransmission;
    case BsdfType::kRoughDielectric: return kLobeGlossyReflection | kLobeGlossyTransmission;
    case BsdfType::kThinDielectric: return kLobeDeltaReflection | kLobeDeltaTransmission;
  }
  return kLobeNone;
}

// Mitsuba's twosided: a back-side query mirrors both directions to the front.
inline bool mirror_to_front(const Bsdf& b, Vec3f* wo, Vec3f* wi) {
  if (!b.two_sided || wo->z >= 0.0f) return false;
  wo->z = -wo->z;
  if (wi) wi->z = -wi->z;
  return true;
}

BsdfEval eval_pdf_front(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi) {
  switch (b.type) {
    case BsdfType::kDiffuse: return lobes::diffuse_eval_pdf(b, uv, wo, wi);
    case BsdfType::kRoughConductor: return lobes::rough_conductor_eval_pdf(b, uv, wo, wi);
    case BsdfType::kPlastic: return lobes::plastic_eval_pdf(b, uv, wo, wi);
    case BsdfType::kRoughPlastic: return lobes::rough_plastic_eval_pdf(b, uv, wo, wi);
    case BsdfType::kRoughDielectric: return lobes::rough_dielectric_eval_pdf(b, uv, wo, wi);
    case BsdfType::kConductor:
    case BsdfType::kDielectric:
    case BsdfType::kThinDielectric: return {};  // Dirac lobes only
  }
  return {};
}

}  // namespace

void Bsdf::finalize() {
  lobes = lobes_of(type);
  float eta_rel = int_ior / ext_ior;
  if (type == BsdfType::kPlastic || type == BsdfType::kRoughPlastic) {
    // Lobe selection weight steering samples by the lobes' mean albedo.
    float d_mean = texture_scalar_mean(reflectance), s_mean = texture_scalar_mean(specular_reflectance);
    specular_sampling_weight = s_mean / (d_mean + s_mean);
    fdr_int = fresnel_diffuse_reflectance(1.0f / eta_rel);
    fdr_ext = fresnel_diffuse_reflectance(eta_rel);
  }
  if (type == BsdfType::kRoughPlastic) lobes::rough_plastic_precompute(this);
}

float Bsdf::roughness() const {
  switch (type) {
    case BsdfType::kDiffuse: return std::numeric_limits<float>::infinity();
    case BsdfType::kRoughConductor:
    case BsdfType::kRoughDielectric: return std::max(std::min(alpha_u, alpha_v), 1e-4f);
    case BsdfType::kRoughPlastic: return std::max(alpha_u, 1e-4f);
    case BsdfType::kConductor:
    case BsdfType::kPlastic:
    case BsdfType::kDielectric:
    case BsdfType::kThinDielectric: return 0.0f;
  }
  return 0.0f;
}

float bsdf_lobe_roughness(const Bsdf& bsdf, uint32_t lobe) {
  if (lobe & kLobeDiffuseReflection) return std::numeric_limits<float>::infinity();
  if (lobe & kLobeDelta) return 0.0f;
  if (lobe & kLobeGlossy) {
    float a = bsdf.type == BsdfType::kRoughPlastic ? bsdf.alpha_u : std::min(bsdf.alpha_u, bsdf.alpha_v);
    return std::max(a, 1e-4f);
  }
  return bsdf.roughness();
}

float bsdf_smooth_roughness(const Bsdf& bsdf) {
  // Smooth plastic is the one BSDF whose Dirac lobe sits next to a smooth one.
  if (bsdf.type == BsdfType::kPlastic) return std::numeric_limits<float>::infinity();
  return bsdf.roughness();
}

BsdfEval bsdf_eval_pdf(const Bsdf& bsdf, Vec2f uv, Vec3f wo, Vec3f wi) {
  mirror_to_front(bsdf, &wo, &wi);
  return eval_pdf_front(bsdf, uv, wo, wi);
}

Rgb bsdf_eval(const Bsdf& bsdf, Vec2f uv, Vec3f wo, Vec3f wi) { return bsdf_eval_pdf(bsdf, uv, wo, wi).value; }

float bsdf_pdf(const Bsdf& bsdf, Vec2f uv, Vec3f wo, Vec3f wi) { return bsdf_eval_pdf(bsdf, uv, wo, wi).pdf; }

namespace {

// Never hand NaN/Inf to the integrator: a degenerate sample ends the path.
bool accept_sample(bool ok, bool mirrored, BsdfSample s, BsdfSample* out) {
  if (!ok || !is_finite(s.weight) || !std::isfinite(s.pdf) || !is_finite(s.wi) || !(s.pdf > 0.0f)) return false;
  if (mirrored) s.wi.z = -s.wi.z;
  *out = s;
  return true;
}

}  // namespace

bool bsdf_sample(const Bsdf& bsdf, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u_dir, BsdfSample* out) {
  bool mirrored = mirror_to_front(bsdf, &wo, nullptr);
  BsdfSample s;
  bool ok = false;
  switch (bsdf.type) {
    case BsdfType::kDiffuse: ok = lobes::diffuse_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
    case BsdfType::kConductor: ok = lobes::conductor_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
    case BsdfType::kRoughConductor: ok = lobes::rough_conductor_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
    case BsdfType::kPlastic: ok = lobes::plastic_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
    case BsdfType::kRoughPlastic: ok = lobes::rough_plastic_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
    case BsdfType::kDielectric: ok = lobes::dielectric_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
    case BsdfType::kRoughDielectric: ok = lobes::rough_dielectric_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
    case BsdfType::kThinDielectric: ok = lobes::thin_dielectric_sample(bsdf, uv, wo, u_lobe, u_dir, &s); break;
  }
  return accept_sample(ok, mirrored, s, out);
}

bool bsdf_start_slope_inversion(const Bsdf& bsdf, Vec3f wo, float u_lobe, Vec2f u_dir, BeckmannSlopeInversion* inv) {
  mirror_to_front(bsdf, &wo, nullptr);
  switch (bsdf.type) {
    case BsdfType::kRoughConductor: return lobes::rough_conductor_start_slope_inversion(bsdf, wo, u_dir, inv);
    case BsdfType::kRoughPlastic: return lobes::rough_plastic_start_slope_inversion(bsdf, wo, u_lobe, u_dir, inv);
    case BsdfType::kRoughDielectric: return lobes::rough_dielectric_start_slope_inversion(bsdf, wo, u_dir, inv);
    default: return false;
  }
}

bool bsdf_sample_from_slope(const Bsdf& bsdf, Vec2f uv, Vec3f wo, float u_lobe, Vec2f slope11, BsdfSample* out) {
  bool mirrored = mirror_to_front(bsdf, &wo, nullptr);
  BsdfSample s;
  bool ok = false;
  switch (bsdf.type) {
    case BsdfType::kRoughConductor: ok = lobes::rough_conductor_sample_from_slope(bsdf, uv, wo, slope11, &s); break;
    case BsdfType::kRoughPlastic: ok = lobes::rough_plastic_sample_from_slope(bsdf, uv, wo, slope11, &s); break;
    case BsdfType::kRoughDielectric:
      ok = lobes::rough_dielectric_sample_from_slope(bsdf, uv, wo, u_lobe, slope11, &s);
      break;
    default: return false;  // no inversion was started for it
  }
  return accept_sample(ok, mirrored, s, out);
}

}  // namespace gdvr
