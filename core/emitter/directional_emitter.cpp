#include "core/emitter/directional_emitter.h"

#include <limits>

namespace gdvr {

EmitterSample sample_directional_emitter(const Emitter& em, float select_pdf, EmitterSample es) {
  Vec3f dir = normalize(em.to_world.vector({0, 0, 1}));
  es.d = -dir;
  es.dist = std::numeric_limits<float>::infinity();
  es.delta = true;
  es.pdf = select_pdf;
  es.weight = em.irradiance / select_pdf;
  return es;
}

}  // namespace gdvr
