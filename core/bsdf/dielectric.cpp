// Smooth, rough and thin dielectrics (Mitsuba 3 src/bsdfs/dielectric.cpp,
// roughdielectric.cpp, thindielectric.cpp). Radiance transport: refraction
// scales by eta_ti^2 (solid-angle compression, Veach 1997 sec. 5.2); the rough
// model is Walter et al. 2007 with Mitsuba's half-vector conventions.
#include "core/bsdf/beckmann_slope.h"
#include "core/bsdf/bsdf_lobes.h"
#include "core/bsdf/fresnel.h"
#include "core/bsdf/microfacet.h"

namespace gdvr::lobes {
namespace {

float relative_eta(const Bsdf& b) { return b.int_ior / b.ext_ior; }
Vec3f mulsign(Vec3f v, float s) { return s < 0.0f ? -v : v; }

MicrofacetDistribution distribution(const Bsdf& b) {
  return MicrofacetDistribution(b.distribution, b.alpha_u, b.alpha_v, b.sample_visible);
}

// Walter et al.'s widened sampling lobe; unused with visible-normal sampling.
MicrofacetDistribution sampling_distribution(const Bsdf& b, float cos_theta_o) {
  MicrofacetDistribution d = distribution(b);
  if (!d.sample_visible) d.scale_alpha(1.2f - 0.2f * std::sqrt(std::abs(cos_theta_o)));
  return d;
}

}  // namespace

// ---- Smooth dielectric ----

bool dielectric_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f /*u*/, BsdfSample* s) {
  FresnelResult fr = fresnel_dielectric(wo.z, relative_eta(b));
  float r = fr.f, t = 1.0f - r;
  bool selected_r = u_lobe <= r;
  s->pdf = selected_r ? r : t;
  if (!(s->pdf > 0.0f)) return false;
  if (selected_r) {
    s->wi = reflect_local(wo);
    s->eta = 1.0f;
    s->lobe = kLobeDeltaReflection;
    s->weight = b.specular_reflectance.eval(uv);
  } else {
    s->wi = refract_local(wo, fr.cos_theta_t, fr.eta_ti);
    s->eta = fr.eta_it;
    s->lobe = kLobeDeltaTransmission;
    s->weight = b.specular_transmittance.eval(uv) * sqr(fr.eta_ti);
  }
  return true;
}

// ---- Rough dielectric ----

BsdfEval rough_dielectric_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi) {
  float cos_o = wo.z, cos_i = wi.z;
  if (cos_o == 0.0f) return {};  // perfectly grazing configurations are ignored
  bool is_reflection = cos_o * cos_i > 0.0f;
  float m_eta = relative_eta(b);
  float eta = cos_o > 0.0f ? m_eta : 1.0f / m_eta, inv_eta = 1.0f / eta;
  // Generalised half vector (Walter et al. 2007, eq. 16), on the normal's side.
  Vec3f m = wo + wi * (is_reflection ? 1.0f : eta);
  if (length_squared(m) == 0.0f) return {};
  m = normalize(m);
  m = mulsign(m, m.z);
  float dot_o_m = dot(wo, m), dot_i_m = dot(wi, m);
  if (!(dot_o_m * cos_o > 0.0f && dot_i_m * cos_i > 0.0f)) return {};
  MicrofacetDistribution distr = distribution(b);
  float d = distr.eval(m);
  float f = fresnel_dielectric(dot_o_m, m_eta).f;
  float g = distr.g(wo, wi, m);
  BsdfEval r;
  float dwh_dwi;
  if (is_reflection) {
    r.value = b.specular_reflectance.eval(uv) * (f * d * g / (4.0f * std::abs(cos_o)));
    dwh_dwi = 1.0f / (4.0f * dot_i_m);
  } else {
    float denom = sqr(dot_o_m + eta * dot_i_m);
    if (denom == 0.0f) return {};
    // inv_eta^2: radiance compression across the interface (missing in Walter et al.).
    r.value = b.specular_transmittance.eval(uv) *
              std::abs(sqr(inv_eta) * (1.0f - f) * d * g * eta * eta * dot_o_m * dot_i_m / (cos_o * denom));
    dwh_dwi = eta * eta * dot_i_m / denom;
  }
  float prob = sampling_distribution(b, cos_o).pdf(mulsign(wo, cos_o), m);
  prob *= is_reflection ? f : 1.0f - f;
  r.pdf = prob * std::abs(dwh_dwi);
  if (!std::isfinite(r.pdf) || !is_finite(r.value)) return {};
  return r;
}

namespace {

// rough_dielectric_sample from the sampled microfacet normal m and its pdf.
bool scatter_on_microfacet(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec3f m, float pdf_m, BsdfSample* s) {
  const float cos_o = wo.z;
  MicrofacetDistribution distr = distribution(b);
  if (!(pdf_m > 0.0f)) return false;
  FresnelResult fr = fresnel_dielectric(dot(wo, m), relative_eta(b));
  bool selected_r = u_lobe <= fr.f;
  float pdf = pdf_m * (selected_r ? fr.f : 1.0f - fr.f);
  Rgb weight(1.0f);
  float dwh_dwi;
  if (selected_r) {
    s->wi = reflect(wo, m);
    s->eta = 1.0f;
    s->lobe = kLobeGlossyReflection;
    weight = b.specular_reflectance.eval(uv);
    dwh_dwi = 1.0f / (4.0f * dot(s->wi, m));
    // A reflection about m that leaves through the other side has zero G1.
    if (s->wi.z * cos_o <= 0.0f) return false;
  } else {
    s->wi = refract_about(wo, m, fr.cos_theta_t, fr.eta_ti);
    s->eta = fr.eta_it;
    s->lobe = kLobeGlossyTransmission;
    weight = b.specular_transmittance.eval(uv) * sqr(fr.eta_ti);
    dwh_dwi = sqr(s->eta) * dot(s->wi, m) / sqr(dot(wo, m) + s->eta * dot(s->wi, m));
    if (s->wi.z * cos_o >= 0.0f) return false;
  }
  // Visible normals: f |cos| / pdf reduces to G1(wi). Otherwise D G |wo.m| / (|cos_o| pdf_m).
  // Mitsuba 3 writes the latter as G (wo.m) / (cos_o cos_m), which drops D / pdf_m and is
  // only right without Walter's widened sampling lobe; we keep weight = eval / pdf.
  float g_weight = distr.sample_visible
                       ? distr.smith_g1(s->wi, m)
                       : distr.g(wo, s->wi, m) * distr.eval(m) * std::abs(dot(wo, m)) / (std::abs(cos_o) * pdf_m);
  s->weight = weight * g_weight;
  s->pdf = pdf * std::abs(dwh_dwi);
  return s->pdf > 0.0f && std::isfinite(s->pdf) && g_weight > 0.0f;
}

}  // namespace

bool rough_dielectric_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s) {
  const float cos_o = wo.z;
  if (cos_o == 0.0f) return false;
  auto [m, pdf_m] = sampling_distribution(b, cos_o).sample(mulsign(wo, cos_o), u);
  return scatter_on_microfacet(b, uv, wo, u_lobe, m, pdf_m, s);
}

bool rough_dielectric_start_slope_inversion(const Bsdf& b, Vec3f wo, Vec2f u, BeckmannSlopeInversion* inv) {
  const float cos_o = wo.z;
  const MicrofacetDistribution distr = sampling_distribution(b, cos_o);
  if (cos_o == 0.0f || !distr.samples_beckmann_slopes()) return false;
  *inv = BeckmannSlopeInversion(distr.stretched_cos_theta(mulsign(wo, cos_o)), u);
  return true;
}

bool rough_dielectric_sample_from_slope(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f slope11,
                                        BsdfSample* s) {
  const float cos_o = wo.z;
  auto [m, pdf_m] = sampling_distribution(b, cos_o).sample_from_slope(mulsign(wo, cos_o), slope11);
  return scatter_on_microfacet(b, uv, wo, u_lobe, m, pdf_m, s);
}

// ---- Thin dielectric ----

bool thin_dielectric_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f /*u*/, BsdfSample* s) {
  float r = fresnel_dielectric(std::abs(wo.z), relative_eta(b)).f;
  // Internal reflections in the slab: R' = R + T^2 R / (1 - R^2) = 2R / (1 + R).
  r *= 2.0f / (1.0f + r);
  float t = 1.0f - r;
  bool selected_r = u_lobe <= r;
  s->pdf = selected_r ? r : t;
  if (!(s->pdf > 0.0f)) return false;
  s->eta = 1.0f;
  if (selected_r) {
    s->wi = reflect_local(wo);
    s->lobe = kLobeDeltaReflection;
    s->weight = b.specular_reflectance.eval(uv);
  } else {
    s->wi = -wo;  // straight through, no refraction (Mitsuba: a Null lobe)
    s->lobe = kLobeDeltaTransmission;
    s->weight = b.specular_transmittance.eval(uv);
  }
  return true;
}

}  // namespace gdvr::lobes
