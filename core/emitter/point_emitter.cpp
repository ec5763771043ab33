#include "core/emitter/point_emitter.h"

#include <algorithm>
#include <cmath>

namespace gdvr {

EmitterSample sample_point_emitter(const Emitter& em, Vec3f ref_p, float select_pdf, EmitterSample es) {
  Vec3f pos = em.to_world.point(Vec3f(0.0f));
  Vec3f d = pos - ref_p;
  float dist2 = length_squared(d);
  if (!(dist2 > 0)) return es;
  es.dist = std::sqrt(dist2);
  es.d = d / es.dist;
  es.delta = true;
  es.pdf = select_pdf;
  Rgb intensity = em.intensity;
  if (em.type == EmitterType::kSpot) {
    Vec3f local = normalize(em.to_world.inverse().vector(-es.d));
    float cos_theta = local.z;
    float cos_cutoff = std::cos(radians(em.cutoff_angle));
    float cos_beam = std::cos(radians(em.beam_width));
    if (cos_theta <= cos_cutoff) return es;
    if (cos_theta < cos_beam) {
      float falloff = (radians(em.cutoff_angle) - std::acos(cos_theta)) /
                      (radians(em.cutoff_angle) - radians(em.beam_width));
      intensity = intensity * std::clamp(falloff, 0.0f, 1.0f);
    }
  }
  es.weight = intensity / (dist2 * select_pdf);
  return es;
}

}  // namespace gdvr
