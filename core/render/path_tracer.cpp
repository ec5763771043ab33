#include "core/render/path_tracer.h"

#include "core/math/sampling.h"
#include "core/render/russian_roulette.h"

namespace gdvr {

PathSample trace_path(const FrameScene& scene, const PathTracerSettings& settings, const Ray& camera_ray,
                      Sampler& sampler, PathCounters& counters) {
  const Scene& desc = scene.scene();
  PathSample out;
  Rgb throughput(1.0f), result(0.0f);
  float eta = 1.0f;
  Ray ray = camera_ray;
  // State of the previous vertex, for MIS when a BSDF-sampled ray hits an emitter.
  Vec3f prev_p = ray.o;
  float prev_bsdf_pdf = 1.0f;
  bool prev_bsdf_delta = true;

  for (int depth = 0;; ++depth) {
    SurfaceInteraction si;
    ++counters.rays;
    if (counters.ray_log) counters.ray_log->push_back({ray, false});
    // The emitter sample at the vertex this ray finds draws the next three
    // numbers; an environment map's tables miss the cache, so their loads
    // start now and overlap Embree's traversal (frame_scene.h).
    scene.prefetch_next_emitter_sample(sampler);
    bool hit = scene.intersect(ray, &si);

    // ---- Emission seen along the ray, weighted against emitter sampling ----
    if (!(depth == 0 && settings.hide_emitters)) {
      Rgb emitted;
      float emitter_pdf = 0;
      if (!hit) {
        const FrameScene::EnvironmentLookup env = scene.environment_along(ray.d);
        emitted = env.radiance;
        emitter_pdf = env.pdf;
      } else if (scene.emitter_of_shape(si.shape) >= 0) {
        emitted = scene.eval_area_emitter(si);
        if (!prev_bsdf_delta && !emitted.is_black()) emitter_pdf = scene.pdf_emitter_direction(prev_p, si);
      }
      if (!emitted.is_black()) {
        float w = prev_bsdf_delta ? 1.0f : mis_power(prev_bsdf_pdf, emitter_pdf);
        Rgb contrib = throughput * emitted * w;
        result += contrib;
        if (depth == 0) out.direct += contrib;
      }
    }
    if (!hit) break;
    if (settings.max_depth >= 0 && depth + 1 >= settings.max_depth) break;

    const Shape& shape = desc.shapes[size_t(si.shape)];
    const Bsdf& bsdf = desc.bsdfs[size_t(shape.bsdf)];
    const Vec3f wo = si.wi;

    // ---- Emitter sampling (skipped for purely specular BSDFs) ----
    if (!bsdf.is_delta_only()) {
      float u_select = sampler.next_1d();
      Vec2f u_light = sampler.next_2d();
      EmitterSample es = scene.sample_emitter_direction(si, u_select, u_light);
      if (!es.weight.is_black()) {
        Vec3f wi_local = si.sh_frame.to_local(es.d);
        BsdfEval be = bsdf_eval_pdf(bsdf, si.uv, wo, wi_local);
        const Rgb& f = be.value;
        if (!f.is_black()) {
          const Ray shadow = shadow_ray(si, es);
          ++counters.rays;
          if (counters.ray_log) counters.ray_log->push_back({shadow, true});
          if (!scene.occluded(shadow)) {
            float w = es.delta ? 1.0f : mis_power(es.pdf, be.pdf);
            result += throughput * f * es.weight * w;
          }
        }
      }
    }

    // ---- BSDF sampling ----
    float u_lobe = sampler.next_1d();
    Vec2f u_dir = sampler.next_2d();
    BsdfSample bs;
    if (!bsdf_sample(bsdf, si.uv, wo, u_lobe, u_dir, &bs)) break;
    if (bs.weight.is_black() || !is_finite(bs.weight)) break;
    throughput *= bs.weight;
    eta *= bs.eta;
    Vec3f d = si.sh_frame.to_world(bs.wi);
    ray = si.spawn_ray(d);
    prev_p = si.p;
    prev_bsdf_pdf = bs.pdf;
    prev_bsdf_delta = bs.is_delta();

    // ---- Russian roulette (russian_roulette.h; counted after the bounce) ----
    float throughput_max = max_component(throughput);
    if (!(throughput_max > 0)) break;
    if (depth + 1 >= settings.rr_depth) {
      float q = russian_roulette_survival(throughput_max, eta);
      if (sampler.next_1d() >= q) break;
      throughput *= 1.0f / q;
    }
  }

  if (!is_finite(result)) {
    ++counters.invalid_samples;
    return PathSample{};
  }
  out.radiance = result;
  return out;
}

}  // namespace gdvr
