// Smooth and rough conductors (Mitsuba 3 src/bsdfs/conductor.cpp and
// roughconductor.cpp): Fresnel for a complex IOR per RGB channel, times
// specular_reflectance; the rough one is the Torrance-Sparrow microfacet model
// f = F D G / (4 cos_o cos_i) with Smith G (Walter et al. 2007).
#include "core/bsdf/beckmann_slope.h"
#include "core/bsdf/bsdf_lobes.h"
#include "core/bsdf/fresnel.h"
#include "core/bsdf/microfacet.h"

namespace gdvr::lobes {
namespace {

MicrofacetDistribution distribution(const Bsdf& b) {
  return MicrofacetDistribution(b.distribution, b.alpha_u, b.alpha_v, b.sample_visible);
}

}  // namespace

bool conductor_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float /*u_lobe*/, Vec2f /*u*/, BsdfSample* s) {
  if (wo.z <= 0.0f) return false;
  s->wi = reflect_local(wo);
  s->pdf = 1.0f;
  s->eta = 1.0f;
  s->lobe = kLobeDeltaReflection;
  s->weight = fresnel_conductor(wo.z, b.eta, b.k) * b.specular_reflectance.eval(uv);
  return true;
}

BsdfEval rough_conductor_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return {};
  Vec3f h = normalize(wo + wi);
  // Micro- and macro-surface must agree on the side (also enforced by G1).
  if (dot(wo, h) <= 0.0f || dot(wi, h) <= 0.0f) return {};
  MicrofacetDistribution distr = distribution(b);
  float d = distr.eval(h);
  if (d == 0.0f) return {};
  float g1_o = distr.smith_g1(wo, h);
  float g = g1_o * distr.smith_g1(wi, h);
  Rgb f = fresnel_conductor(dot(wo, h), b.eta, b.k) * b.specular_reflectance.eval(uv);
  BsdfEval r;
  r.value = f * (d * g / (4.0f * wo.z));
  // Visible normals: pdf = D G1(wo) / (4 cos_o); otherwise D cos_h / (4 wi.h).
  r.pdf = distr.sample_visible ? d * g1_o / (4.0f * wo.z) : distr.pdf(wo, h) / (4.0f * dot(wi, h));
  return r;
}

namespace {

// rough_conductor_sample from the sampled microfacet normal m and its pdf.
bool reflect_on_microfacet(const Bsdf& b, const MicrofacetDistribution& distr, Vec2f uv, Vec3f wo, Vec3f m,
                           float pdf_m, BsdfSample* s) {
  Vec3f wi = reflect(wo, m);
  float wi_dot_m = dot(wi, m);
  if (!(pdf_m > 0.0f) || wi.z <= 0.0f || !(wi_dot_m > 0.0f)) return false;
  float weight = distr.sample_visible ? distr.smith_g1(wi, m)
                                      : distr.g(wo, wi, m) * dot(wo, m) / (wo.z * m.z);
  s->wi = wi;
  s->pdf = pdf_m / (4.0f * wi_dot_m);  // Jacobian of the half-vector mapping
  s->eta = 1.0f;
  s->lobe = kLobeGlossyReflection;
  s->weight = fresnel_conductor(dot(wo, m), b.eta, b.k) * b.specular_reflectance.eval(uv) * weight;
  return s->pdf > 0.0f;
}

}  // namespace

bool rough_conductor_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float /*u_lobe*/, Vec2f u, BsdfSample* s) {
  if (wo.z <= 0.0f) return false;
  MicrofacetDistribution distr = distribution(b);
  auto [m, pdf_m] = distr.sample(wo, u);
  return reflect_on_microfacet(b, distr, uv, wo, m, pdf_m, s);
}

bool rough_conductor_start_slope_inversion(const Bsdf& b, Vec3f wo, Vec2f u, BeckmannSlopeInversion* inv) {
  MicrofacetDistribution distr = distribution(b);
  if (wo.z <= 0.0f || !distr.samples_beckmann_slopes()) return false;
  *inv = BeckmannSlopeInversion(distr.stretched_cos_theta(wo), u);
  return true;
}

bool rough_conductor_sample_from_slope(const Bsdf& b, Vec2f uv, Vec3f wo, Vec2f slope11, BsdfSample* s) {
  MicrofacetDistribution distr = distribution(b);
  auto [m, pdf_m] = distr.sample_from_slope(wo, slope11);
  return reflect_on_microfacet(b, distr, uv, wo, m, pdf_m, s);
}

}  // namespace gdvr::lobes
