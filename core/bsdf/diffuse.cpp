// Lambertian reflection (Mitsuba 3 src/bsdfs/diffuse.cpp), one-sided.
#include "core/bsdf/bsdf_lobes.h"
#include "core/bsdf/microfacet.h"

namespace gdvr::lobes {

BsdfEval diffuse_eval_pdf(const Bsdf& b, Vec2f uv, Vec3f wo, Vec3f wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return {};
  float pdf = square_to_cosine_hemisphere_pdf(wi);
  return {b.reflectance.eval(uv) * pdf, pdf};
}

bool diffuse_sample(const Bsdf& b, Vec2f uv, Vec3f wo, float /*u_lobe*/, Vec2f u, BsdfSample* s) {
  if (wo.z <= 0.0f) return false;
  s->wi = square_to_cosine_hemisphere(u);
  s->pdf = square_to_cosine_hemisphere_pdf(s->wi);
  if (!(s->pdf > 0.0f)) return false;
  s->eta = 1.0f;
  s->lobe = kLobeDiffuseReflection;
  // f cos / pdf = (R / pi) cos / (cos / pi).
  s->weight = b.reflectance.eval(uv);
  return true;
}

}  // namespace gdvr::lobes
