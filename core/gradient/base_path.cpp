#include "core/gradient/base_path.h"

#include "core/math/sampling.h"
#include "core/render/russian_roulette.h"

namespace gdvr {

void mark_dark_suffixes(PathRecord* record) {
  // From the end of the path backwards.
  bool dark_after = true;  // nothing from x_{k+1} on (emission included)
  for (size_t k = record->v.size(); k-- > 0;) {
    PathVertex& v = record->v[k];
    const bool lit_here = (v.has_nee && v.nee_visible) || (v.next == PathNext::kEscaped && !v.escape_le.is_black());
    v.dark_suffix = dark_after && !lit_here;
    dark_after = v.dark_suffix && v.le.is_black();
  }
}

// Flattened, as the path tracer's batch driver (path_batch.cpp): its callees are
// inlined into the vertex loop (hit shading, light and BSDF sampling).
[[gnu::flatten]] void trace_base_path(const FrameScene& scene, const PathTracerSettings& settings, const CameraHit& first,
                     Sampler& sampler, PathCounters& counters, PathRecord* record) {
  const Scene& desc = scene.scene();
  PathRecord& rec = *record;
  rec.clear();
  rec.camera_ray = first.ray;
  Rgb beta(1.0f);
  float eta = 1.0f;
  Ray ray = first.ray;

  if (!first.hit) {
    if (!settings.hide_emitters) rec.direct = scene.eval_environment(ray.d);
    if (!is_finite(rec.direct)) {
      ++counters.invalid_samples;
      rec.clear();
      rec.invalid = true;
    }
    return;
  }

  // Each vertex's hit is written in place into the record (a copy of a just
  // written SurfaceInteraction stalls on store-to-load forwarding).
  rec.v.emplace_back();
  rec.v.back().si = first.si;
  for (int depth = 0;; ++depth) {
    PathVertex& v = rec.v.back();  // valid until the next vertex is appended
    const SurfaceInteraction& si = v.si;
    v.beta = beta;
    const Shape& shape = desc.shapes[size_t(si.shape)];
    v.bsdf = shape.bsdf;
    const Bsdf& bsdf = desc.bsdfs[size_t(shape.bsdf)];

    // ---- Emission at x_k (the previous vertex's BSDF sample), MIS against emitter sampling ----
    if (scene.emitter_of_shape(si.shape) >= 0) {
      v.le = scene.eval_area_emitter(si);
      if (depth == 0) {
        v.w_emit = 1.0f;
        if (!settings.hide_emitters) rec.direct = v.le;
      } else if (!v.le.is_black()) {
        const PathVertex& prev = rec.v[rec.v.size() - 2];
        if (prev.bs.is_delta()) {
          v.w_emit = 1.0f;
        } else {
          v.emitter_pdf = scene.pdf_emitter_direction(prev.si.p, si);
          v.w_emit = mis_power(prev.bs.pdf, v.emitter_pdf);
        }
        v.emission = beta * v.le * v.w_emit;
        rec.indirect += v.emission;
      }
    }
    if (depth + 1 >= path_depth_limit(settings)) break;
    const Vec3f wo = si.wi;

    // ---- Emitter sampling (skipped for purely specular BSDFs) ----
    if (!bsdf.is_delta_only()) {
      v.has_nee = true;
      v.u_select = sampler.next_1d();
      v.u_light = sampler.next_2d();
      // Computed on a local and recorded at the end, as for the hit above.
      const EmitterSample es = scene.sample_emitter_direction(si, v.u_select, v.u_light);
      if (!es.weight.is_black()) {
        Vec3f wl = si.sh_frame.to_local(es.d);
        BsdfEval be = bsdf_eval_pdf(bsdf, si.uv, wo, wl);
        v.nee_f = be.value;
        v.w_nee = es.delta ? 1.0f : mis_power(es.pdf, be.pdf);
        if (!be.value.is_black()) {
          ++counters.rays;
          v.nee_visible = !scene.occluded(shadow_ray(si, es));
          if (v.nee_visible) {
            v.nee = beta * be.value * es.weight * v.w_nee;
            rec.indirect += v.nee;
          }
        }
      }
      v.es = es;
    }

    // ---- BSDF sampling ----
    v.u_lobe = sampler.next_1d();
    v.u_dir = sampler.next_2d();
    if (!bsdf_sample(bsdf, si.uv, wo, v.u_lobe, v.u_dir, &v.bs)) break;
    if (v.bs.weight.is_black() || !is_finite(v.bs.weight)) break;
    beta *= v.bs.weight;
    eta *= v.bs.eta;
    const Vec3f d = si.sh_frame.to_world(v.bs.wi);
    ray = si.spawn_ray(d);

    // ---- Russian roulette (russian_roulette.h; counted after the bounce) ----
    float throughput_max = max_component(beta);
    if (!(throughput_max > 0)) break;
    if (depth + 1 >= settings.rr_depth) {
      float q = russian_roulette_survival(throughput_max, eta);
      if (sampler.next_1d() >= q) {
        v.next = PathNext::kKilled;
        v.rr_q = q;
        break;
      }
      v.rr_q = q;
      beta *= 1.0f / q;
    }

    // ---- The next vertex, intersected into a new record entry (dropped if the ray escapes) ----
    ++counters.rays;
    // As in trace_path: the next vertex's emitter sample draws the next three
    // numbers, and an environment map's tables for them start loading now,
    // overlapping the traversal.
    scene.prefetch_next_emitter_sample(sampler);
    rec.v.emplace_back();  // `v` and `si` may move: only indices from here on
    const bool hit = scene.intersect(ray, &rec.v.back().si);
    if (!hit) rec.v.pop_back();
    PathVertex& left = hit ? rec.v[rec.v.size() - 2] : rec.v.back();
    if (!hit) {
      left.next = PathNext::kEscaped;
      left.escape_dir = d;
      // Radiance and pdf from one direction-to-uv conversion.
      const FrameScene::EnvironmentLookup env = scene.environment_along(d);
      left.escape_le = env.radiance;
      if (!left.escape_le.is_black()) {
        left.escape_pdf = left.bs.is_delta() ? 0.0f : env.pdf;
        left.w_escape = left.bs.is_delta() ? 1.0f : mis_power(left.bs.pdf, left.escape_pdf);
        left.escape = beta * left.escape_le * left.w_escape;
        rec.indirect += left.escape;
      }
      break;
    }
    left.next = PathNext::kSurface;
  }

  mark_dark_suffixes(&rec);

  if (!is_finite(rec.indirect) || !is_finite(rec.direct)) {
    ++counters.invalid_samples;
    rec.clear();
    rec.invalid = true;
  }
}

}  // namespace gdvr
