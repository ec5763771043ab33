#include "core/render/path_tracer.h"

#include "core/render/path_stages.h"

namespace gdvr {

PathSample trace_path(const FrameScene& scene, const PathTracerSettings& settings, const Ray& camera_ray,
                      Sampler& sampler, PathCounters& counters) {
  PathState st;
  start_path(&st, camera_ray, sampler);
  do {
    prefetch_for_next_vertex(scene, st);
    cast_closest(scene, settings, &st, counters);
    add_emission(scene, settings, &st);
    if (!st.continues) break;
    sample_emitter(scene, &st);
    connect_emitter(&st);
    sample_bsdf(settings, &st);
    if (st.shadow_pending) resolve_shadow(cast_shadow(scene, st, counters), &st);
  } while (st.continues);
  sampler = st.sampler;
  return finish_path(scene, st, counters);
}

}  // namespace gdvr
