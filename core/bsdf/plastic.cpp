// Smooth and rough plastic (Mitsuba 3 src/bsdfs/plastic.cpp, roughplastic.cpp):
// a dielectric coating over a Lambertian base with internal scattering.
// Smooth: f_d = R / (1 - Fdr_int) * (1 - F(wo)) (1 - F(wi)) / (pi eta^2)
// (Weidlich & Wilkie 2007 with Mitsuba's energy normalisation); with
// `nonlinear`, the denominator is 1 - R Fdr_int. Rough: the Fresnel
// transmittances become the rough interface's directional transmittance
// t(cos) tabulated by finalize(), as Mitsuba precomputes.
#include <map>
#include <mutex>
#include <tuple>

#include "core/bsdf/beckmann_slope.h"
#include "core/bsdf/bsdf_lobes.h"
#include "core/bsdf/fresnel.h"
#include "core/bsdf/microfacet.h"

namespace gdvr {

Rgb plastic_diffuse_base(const Bsdf& b, Rgb reflectance, float internal_reflectance) {
  Rgb denom =
      b.nonlinear ? Rgb(1.0f) - reflectance * internal_reflectance : Rgb(1.0f - internal_reflectance);
  return reflectance / denom;
}

namespace lobes {
namespace {

float relative_eta(const Bsdf& b) { return b.int_ior / b.ext_ior; }

Rgb diffuse_base(const Bsdf& b, Vec2f uv, float internal_reflectance) {
  return plastic_diffuse_base(b, b.reflectance.eval(uv), internal_reflectance);
}

// Mitsuba's lerp_gather over the table sampled at cos = i / (res - 1).
float lerp_table(const Bsdf& b, float cos_theta) {
  constexpr int kRes = Bsdf::kRoughTransmittanceRes;
  float x = cos_theta * float(kRes - 1);
  int index = std::min(int(x), kRes - 2);
  index = std::max(index, 0);
  float t = x - float(index);
  return (1.0f - t) * b.rough_transmittance[index] + t * b.rough_transmittance[index + 1];
}

MicrofacetDistribution rough_plastic_distribution(const Bsdf& b) {
  // roughplastic is isotropic in Mitsuba (anisotropic alphas are rejected).
  return MicrofacetDistribution(b.distribution, b.alpha_u, b.alpha_u, b.sample_visible);
}

}  // namespace

// ---- Smooth plastic ----

BsdfEval plastic_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return {};
  float eta = relative_eta(b);
  float f_o = fresnel_dielectric(wo.z, eta).f, f_i = fresnel_dielectric(wi.z, eta).f;
  float cos_pdf = square_to_cosine_hemisphere_pdf(wi);
  BsdfEval r;
  r.value = diffuse_base(b, uv, b.fdr_int) * (cos_pdf * (1.0f / (eta * eta)) * (1.0f - f_o) * (1.0f - f_i));
  float w = b.specular_sampling_weight;
  float prob_specular = f_o * w, prob_diffuse = (1.0f - f_o) * (1.0f - w);
  r.pdf = cos_pdf * prob_diffuse / (prob_specular + prob_diffuse);
  return r;
}

bool plastic_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s) {
  if (wo.z <= 0.0f) return false;
  float eta = relative_eta(b);
  float f_o = fresnel_dielectric(wo.z, eta).f;
  float w = b.specular_sampling_weight;
  // Lobe selection proportional to Fresnel times the lobe's mean albedo.
  float prob_specular = f_o * w, prob_diffuse = (1.0f - f_o) * (1.0f - w);
  prob_specular = prob_specular / (prob_specular + prob_diffuse);
  prob_diffuse = 1.0f - prob_specular;
  s->eta = 1.0f;
  if (u_lobe < prob_specular) {
    s->wi = reflect_local(wo);
    s->pdf = prob_specular;
    s->lobe = kLobeDeltaReflection;
    s->weight = b.specular_reflectance.eval(uv) * (f_o / prob_specular);
    return true;
  }
  s->wi = square_to_cosine_hemisphere(u);
  s->pdf = prob_diffuse * square_to_cosine_hemisphere_pdf(s->wi);
  s->lobe = kLobeDiffuseReflection;
  if (!(s->pdf > 0.0f)) return false;
  float f_i = fresnel_dielectric(s->wi.z, eta).f;
  s->weight = diffuse_base(b, uv, b.fdr_int) * ((1.0f / (eta * eta)) * (1.0f - f_o) * (1.0f - f_i) / prob_diffuse);
  return true;
}

// ---- Rough plastic ----

void rough_plastic_precompute(Bsdf* b) {
  constexpr int kRes = Bsdf::kRoughTransmittanceRes;
  float eta = relative_eta(*b);
  // Mitsuba builds these tables with visible-normal sampling regardless of the
  // BSDF's sample_visible flag. ~1M microfacet samples: cache per parameter set,
  // since scenes and animations re-finalize the same materials.
  MicrofacetDistribution distr(b->distribution, b->alpha_u, b->alpha_u, /*visible = */ true);
  using Key = std::tuple<int, float, float>;
  struct Tables {
    std::array<float, kRes> transmittance;
    float internal_reflectance;
  };
  static std::mutex mutex;
  static std::map<Key, Tables> cache;
  Key key{int(distr.type), distr.alpha_u, eta};
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(key);
    if (it != cache.end()) {
      b->rough_transmittance = it->second.transmittance;
      b->rough_internal_reflectance = it->second.internal_reflectance;
      return;
    }
  }
  Tables t;
  float internal = 0.0f;
  for (int i = 0; i < kRes; ++i) {
    float mu = std::max(1e-6f, float(i) / float(kRes - 1));
    Vec3f wi(std::sqrt(1.0f - mu * mu), 0.0f, mu);
    t.transmittance[i] = microfacet_eval_transmittance(distr, wi, eta);
    internal += microfacet_eval_reflectance(distr, wi, 1.0f / eta) * wi.z;
  }
  // Cosine-weighted hemispherical mean of the internal reflectance (2 * mean(R mu)).
  t.internal_reflectance = internal / float(kRes) * 2.0f;
  b->rough_transmittance = t.transmittance;
  b->rough_internal_reflectance = t.internal_reflectance;
  std::lock_guard<std::mutex> lock(mutex);
  cache.emplace(key, t);
}

namespace {

struct RoughPlasticProbs {
  float specular, diffuse;
};

RoughPlasticProbs rough_plastic_probs(const Bsdf& b, float t_o) {
  float w = b.specular_sampling_weight;
  float ps = (1.0f - t_o) * w, pd = t_o * (1.0f - w);
  ps = ps / (ps + pd);
  return {ps, 1.0f - ps};
}

}  // namespace

BsdfEval rough_plastic_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return {};
  float eta = relative_eta(b);
  float t_o = lerp_table(b, wo.z), t_i = lerp_table(b, wi.z);
  RoughPlasticProbs probs = rough_plastic_probs(b, t_o);
  MicrofacetDistribution distr = rough_plastic_distribution(b);
  Vec3f h = normalize(wo + wi);
  float d = distr.eval(h);
  float g1_o = distr.smith_g1(wo, h);
  float pdf_specular = distr.sample_visible ? d * g1_o / (4.0f * wo.z) : distr.pdf(wo, h) / (4.0f * dot(wi, h));
  BsdfEval r;
  r.pdf = probs.specular * pdf_specular + probs.diffuse * square_to_cosine_hemisphere_pdf(wi);
  float f = fresnel_dielectric(dot(wo, h), eta).f;
  float g = distr.smith_g1(wi, h) * g1_o;
  r.value = b.specular_reflectance.eval(uv) * (f * d * g / (4.0f * wo.z));
  r.value += diffuse_base(b, uv, b.rough_internal_reflectance) *
             (kInvPi / (eta * eta) * wi.z * t_o * t_i);
  return r;
}

namespace {

// rough_plastic_sample once its direction is chosen: Mitsuba evaluates the
// full mixture pdf/value for either lobe (MIS-like).
bool finish_rough_plastic_sample(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi, uint32_t lobe, BsdfSample* s) {
  s->wi = wi;
  s->lobe = lobe;
  BsdfEval e = rough_plastic_eval_pdf(b, uv, wo, s->wi);
  if (!(e.pdf > 0.0f)) return false;
  s->pdf = e.pdf;
  s->eta = 1.0f;
  s->weight = e.value / e.pdf;
  return true;
}

bool samples_specular_lobe(const Bsdf& b, Vec3f wo, float u_lobe) {
  return u_lobe < rough_plastic_probs(b, lerp_table(b, wo.z)).specular;
}

}  // namespace

bool rough_plastic_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float u_lobe, Vec2f u, BsdfSample* s) {
  if (wo.z <= 0.0f) return false;
  if (samples_specular_lobe(b, wo, u_lobe))
    return finish_rough_plastic_sample(b, uv, wo, reflect(wo, rough_plastic_distribution(b).sample(wo, u).first),
                                       kLobeGlossyReflection, s);
  return finish_rough_plastic_sample(b, uv, wo, square_to_cosine_hemisphere(u), kLobeDiffuseReflection, s);
}

bool rough_plastic_start_slope_inversion(const Bsdf& b, Vec3f wo, float u_lobe, Vec2f u, BeckmannSlopeInversion* inv) {
  const MicrofacetDistribution distr = rough_plastic_distribution(b);
  if (wo.z <= 0.0f || !distr.samples_beckmann_slopes() || !samples_specular_lobe(b, wo, u_lobe)) return false;
  *inv = BeckmannSlopeInversion(distr.stretched_cos_theta(wo), u);
  return true;
}

bool rough_plastic_sample_from_slope(const Bsdf& b, Vec2f uv, Vec3f wo, Vec2f slope11, BsdfSample* s) {
  const Vec3f m = rough_plastic_distribution(b).sample_from_slope(wo, slope11).first;
  return finish_rough_plastic_sample(b, uv, wo, reflect(wo, m), kLobeGlossyReflection, s);
}

}  // namespace lobes
}  // namespace gdvr
