// Beckmann and GGX microfacet distributions with Mitsuba 3's conventions
// (include/mitsuba/render/microfacet.h): anisotropic alpha_u/alpha_v clamped
// to 1e-4, Smith's separable shadowing-masking G, and sampling either of the
// full distribution D(m) cos(theta_m) or of the visible normals (Heitz and
// d'Eon 2014; Beckmann by Jakob's numerical inversion, GGX by Heitz 2018).
#pragma once

#include <utility>

#include "core/bsdf/bsdf.h"
#include "core/math/sampling.h"
#include "core/math/vec.h"

namespace gdvr {

struct MicrofacetDistribution {
  MicrofacetType type = MicrofacetType::kBeckmann;
  float alpha_u = 0.1f, alpha_v = 0.1f;
  bool sample_visible = true;

  MicrofacetDistribution(MicrofacetType t, float au, float av, bool visible);

  bool is_isotropic() const { return alpha_u == alpha_v; }
  // D(m): normal distribution function (zero where it underflows, as Mitsuba).
  float eval(Vec3f m) const;
  // Density of sample() over microfacet normals m, for outgoing direction wi
  // (only used with visible-normal sampling).
  float pdf(Vec3f wi, Vec3f m) const;
  // Samples a microfacet normal; returns {m, pdf(wi, m)}.
  std::pair<Vec3f, float> sample(Vec3f wi, Vec2f u) const;
  // Beckmann visible-normal sampling split at its slope inversion
  // (beckmann_slope.h), for batches that run the inversions side by side:
  // sample(wi, u) is sample_from_slope(wi, BeckmannSlopeInversion::solve(
  // stretched_cos_theta(wi), u)), bit for bit.
  bool samples_beckmann_slopes() const { return sample_visible && type == MicrofacetType::kBeckmann; }
  float stretched_cos_theta(Vec3f wi) const { return stretch(wi).z; }
  std::pair<Vec3f, float> sample_from_slope(Vec3f wi, Vec2f slope11) const {
    return visible_normal_from_slope(wi, stretch(wi), slope11);
  }
  float smith_g1(Vec3f v, Vec3f m) const;
  float g(Vec3f wi, Vec3f wo, Vec3f m) const { return smith_g1(wi, m) * smith_g1(wo, m); }
  // Scales both roughnesses (Walter et al. 2007's sampling trick).
  void scale_alpha(float s) { alpha_u *= s; alpha_v *= s; }

 private:
  // wi in the space where the distribution has alpha = 1.
  Vec3f stretch(Vec3f wi) const { return normalize(Vec3f(alpha_u * wi.x, alpha_v * wi.y, wi.z)); }
  Vec2f sample_visible_11(float cos_theta_i, Vec2f u) const;
  // The visible normal and its pdf from the alpha = 1 slope sampled for wi_p = stretch(wi).
  std::pair<Vec3f, float> visible_normal_from_slope(Vec3f wi, Vec3f wi_p, Vec2f slope11) const;
};

// Inverse error function (Giles 2010, single precision), as Dr.Jit's erfinv.
float erfinv(float x);

// Directional albedo tables of a rough dielectric interface, computed by the
// same Gauss-Legendre quadrature over visible normals as Mitsuba's
// eval_reflectance / eval_transmittance (used by roughplastic).
// Reflectance of the interface for incidence direction wi and relative IOR eta.
float microfacet_eval_reflectance(const MicrofacetDistribution& distr, Vec3f wi, float eta);
float microfacet_eval_transmittance(const MicrofacetDistribution& distr, Vec3f wi, float eta);

}  // namespace gdvr
