// BSDFs of the Mitsuba 3 subset gdvr supports, as one tagged struct with
// switch dispatch (no virtual call per sample). All directions are in the local
// shading frame (z = shading normal) and point away from the surface.
// Conventions follow Mitsuba 3: eval() returns f(wo, wi) * |cos(theta_i)| and
// excludes Dirac lobes; sample() returns weight = f * |cos| / pdf (for a Dirac
// lobe: the lobe's throughput, with pdf set to the discrete selection probability).
#pragma once

#include <array>
#include <cstdint>

#include "core/bsdf/beckmann_slope.h"
#include "core/math/vec.h"
#include "core/texture/texture.h"

namespace gdvr {

enum class BsdfType {
  kDiffuse,
  kConductor,
  kRoughConductor,
  kPlastic,
  kRoughPlastic,
  kDielectric,
  kRoughDielectric,
  kThinDielectric,
};

enum class MicrofacetType { kBeckmann, kGGX };

// Lobe flags, combinable.
enum BsdfLobe : uint32_t {
  kLobeNone = 0,
  kLobeDiffuseReflection = 1u << 0,
  kLobeGlossyReflection = 1u << 1,
  kLobeGlossyTransmission = 1u << 2,
  kLobeDeltaReflection = 1u << 3,
  kLobeDeltaTransmission = 1u << 4,
  kLobeDelta = kLobeDeltaReflection | kLobeDeltaTransmission,
  kLobeGlossy = kLobeGlossyReflection | kLobeGlossyTransmission,
  kLobeTransmission = kLobeGlossyTransmission | kLobeDeltaTransmission,
};

struct Bsdf {
  BsdfType type = BsdfType::kDiffuse;
  bool two_sided = false;  // Mitsuba `twosided` wrapper: back side mirrors the front

  Texture reflectance = Texture::constant(Rgb(0.5f));     // diffuse; plastic's diffuse_reflectance
  Texture specular_reflectance = Texture::constant(Rgb(1.0f));
  Texture specular_transmittance = Texture::constant(Rgb(1.0f));
  Rgb eta{0.0f}, k{1.0f};           // conductor: complex IOR relative to the exterior (default Mitsuba "none" = perfect mirror)
  float int_ior = 1.49f, ext_ior = 1.000277f;  // dielectric / plastic (Mitsuba defaults: polypropylene, air)
  MicrofacetType distribution = MicrofacetType::kBeckmann;
  float alpha_u = 0.1f, alpha_v = 0.1f;
  bool sample_visible = true;
  bool nonlinear = false;           // plastic

  // Derived by finalize(): lobe flags, plastic's specular sampling weight, etc.
  uint32_t lobes = kLobeNone;
  float specular_sampling_weight = 0.5f;
  float fdr_int = 0, fdr_ext = 0;   // plastic: diffuse Fresnel reflectance
  // roughplastic: Mitsuba's precomputed rough-interface transmittance at
  // cos(theta) = i / 63 and the internal diffuse reflectance (roughplastic.cpp).
  static constexpr int kRoughTransmittanceRes = 64;
  std::array<float, kRoughTransmittanceRes> rough_transmittance{};
  float rough_internal_reflectance = 0;
  // Derives the fields above from the parameters. Call once after setting them
  // (and again after changing them); eval/pdf/sample assume it was called.
  void finalize();

  bool has_lobe(uint32_t mask) const { return (lobes & mask) != 0; }
  bool is_delta_only() const { return lobes != 0 && (lobes & ~uint32_t(kLobeDelta)) == 0; }
  // Roughness used by gradient-domain shifts to classify a vertex as diffuse
  // (reconnectable) or glossy/specular (half-vector copy). Diffuse = +infinity.
  float roughness() const;
  // Depends on the orientation of the shading frame around the normal
  // (SurfaceInteraction::sh_frame.s), not only on the normal.
  bool is_anisotropic() const {
    return (type == BsdfType::kRoughConductor || type == BsdfType::kRoughDielectric) && alpha_u != alpha_v;
  }
};

// Roughness of one sampled lobe (BsdfSample::lobe): +inf for diffuse lobes,
// alpha (the smaller of alpha_u/alpha_v) for glossy lobes, 0 for Dirac lobes.
// Plastic mixes a Dirac and a diffuse lobe, so shifts should classify by lobe.
float bsdf_lobe_roughness(const Bsdf& bsdf, uint32_t lobe);

// Smallest roughness among the BSDF's non-Dirac lobes (+inf for a diffuse
// lobe), 0 when it has only Dirac lobes: how rough a vertex is for a direction
// that was not sampled from a Dirac lobe (smooth plastic: its diffuse base).
float bsdf_smooth_roughness(const Bsdf& bsdf);

struct BsdfSample {
  Vec3f wi;
  float pdf = 0;         // solid-angle pdf; for Dirac lobes the discrete lobe probability
  Rgb weight;            // f * |cos| / pdf
  float eta = 1;         // relative IOR crossed, Mitsuba's eta_it (1 for reflection)
  uint32_t lobe = kLobeNone;
  bool is_delta() const { return (lobe & kLobeDelta) != 0; }
};

// f * |cos theta_i| and the solid-angle pdf of sampling wi given wo, in one call
// (shares the half vector, D, G1 and Fresnel terms). Dirac lobes excluded.
struct BsdfEval {
  Rgb value;
  float pdf = 0;
};

Rgb bsdf_eval(const Bsdf& bsdf, Vec2f uv, Vec3f wo, Vec3f wi);
float bsdf_pdf(const Bsdf& bsdf, Vec2f uv, Vec3f wo, Vec3f wi);
BsdfEval bsdf_eval_pdf(const Bsdf& bsdf, Vec2f uv, Vec3f wo, Vec3f wi);
// A sample that leaves the direction as it was: a thin dielectric's
// transmission (Mitsuba 3 flags it a "null" interaction).
inline bool passes_straight_through(const Bsdf& bsdf, const BsdfSample& s) {
  return bsdf.type == BsdfType::kThinDielectric && (s.lobe & kLobeDeltaTransmission) != 0;
}

// u_lobe selects among lobes, u_dir samples the direction. Returns false when no
// direction could be sampled (the path ends).
bool bsdf_sample(const Bsdf& bsdf, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u_dir, BsdfSample* out);

// bsdf_sample split at a Beckmann visible-slope inversion (beckmann_slope.h),
// for a batch of paths that runs its inversions side by side
// (path_batch.cpp). Where bsdf_sample would draw its microfacet normal by
// such an inversion (the rough conductor, plastic and dielectric with
// Beckmann visible-normal sampling, where the sample reaches the microfacet
// lobe), starts it in *inv and returns true; then bsdf_sample_from_slope with
// the same numbers and inv->slope() after its Newton steps returns what
// bsdf_sample returns, bit for bit. Otherwise returns false: call bsdf_sample.
bool bsdf_start_slope_inversion(const Bsdf& bsdf, Vec3f wo, float u_lobe, Vec2f u_dir, BeckmannSlopeInversion* inv);
bool bsdf_sample_from_slope(const Bsdf& bsdf, Vec2f uv, Vec3f wo, float u_lobe, Vec2f slope11, BsdfSample* out);

// Plastic's diffuse base for a diffuse reflectance R: R / (1 - Fdr), or with
// `nonlinear` R / (1 - R Fdr), Fdr the internal diffuse Fresnel reflectance
// (smooth plastic: fdr_int). plastic.cpp scales it by the Fresnel
// transmittances; the vector path batch keeps it per triangle (vector_scene.cpp).
Rgb plastic_diffuse_base(const Bsdf& b, Rgb reflectance, float internal_reflectance);

}  // namespace gdvr
