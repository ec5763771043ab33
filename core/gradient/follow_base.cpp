#include "core/gradient/follow_base.h"

#include <cmath>

#include "core/gradient/half_vector_copy.h"
#include "core/math/sampling.h"

namespace gdvr {
namespace {

// Samples exactly the Dirac lobe `lobe` at the offset vertex. The lobe is part
// of the path, not the random number that chose it, so try the base's u_lobe
// first and then both ends of the selection interval (lobe selection is a
// threshold on u_lobe for every BSDF here).
bool sample_dirac_lobe(const Bsdf& bsdf, const SurfaceInteraction& si, uint32_t lobe, float u_lobe, BsdfSample* out) {
  for (float u : {u_lobe, 0.0f, 0.99999994f, 0.5f}) {
    BsdfSample s;
    if (bsdf_sample(bsdf, si.uv, si.wi, u, Vec2f(0.5f, 0.5f), &s) && s.lobe == lobe && !s.weight.is_black() &&
        is_finite(s.weight) && s.pdf > 0) {
      *out = s;
      return true;
    }
  }
  return false;
}

}  // namespace

bool follow_base_bounce(const Bsdf& bsdf_o, const SurfaceInteraction& so, const PathVertex& v, bool replay, float inv_q,
                        Rgb* beta, double* ratio, FollowedBounce* out) {
  if (replay) {
    // Replay: same random numbers; in path space the Jacobian is p_b/p_o, so the ratio stays 1.
    BsdfSample s;
    if (!bsdf_sample(bsdf_o, so.uv, so.wi, v.u_lobe, v.u_dir, &s) || s.weight.is_black() || !is_finite(s.weight))
      return false;
    *beta *= s.weight * inv_q;
    out->wi = s.wi, out->pdf = s.pdf, out->delta = s.is_delta(), out->sample = s;
    return true;
  }
  if (v.bs.is_delta()) {
    // Dirac lobe: the offset takes the same lobe (the half vector is the normal; Jacobian 1).
    BsdfSample s;
    if (!sample_dirac_lobe(bsdf_o, so, v.bs.lobe, v.u_lobe, &s)) return false;
    *beta *= s.weight * (s.pdf * inv_q / v.bs.pdf);
    *ratio *= double(s.pdf) / double(v.bs.pdf);
    out->wi = s.wi, out->pdf = s.pdf, out->delta = true, out->sample = s;
    return true;
  }
  HalfVectorCopy hv;
  if (!copy_half_vector(v.si.wi, v.bs.wi, v.bs.eta, so.wi, &hv)) return false;
  BsdfEval be = bsdf_eval_pdf(bsdf_o, so.uv, so.wi, hv.wi);
  if (!(be.pdf > 0) || be.value.is_black()) return false;
  *beta *= be.value * (hv.jacobian * inv_q / v.bs.pdf);
  *ratio *= double(be.pdf) * double(hv.jacobian) / double(v.bs.pdf);
  out->wi = hv.wi, out->pdf = be.pdf, out->delta = false;
  out->sample = v.bs;
  out->sample.wi = hv.wi, out->sample.pdf = be.pdf, out->sample.weight = be.value / be.pdf;
  return true;
}

Rgb offset_emitter_sampling(const FrameScene& scene, const SurfaceInteraction& so, const Bsdf& bsdf_o,
                            const PathVertex& v, Rgb beta, double* ratio, PathCounters& counters, bool same_emitters) {
  if (bsdf_o.is_delta_only()) {
    *ratio = 0.0;  // the offset has no emitter sampling here: only the base generates this pair
    return Rgb(0.0f);
  }
  const EmitterSample eo =
      same_emitters && std::isinf(v.es.dist) ? v.es : scene.sample_emitter_direction(so, v.u_select, v.u_light);
  if (!(eo.pdf > 0) || !(v.es.pdf > 0)) {
    *ratio = 0.0;
    return Rgb(0.0f);
  }
  if (eo.weight.is_black()) return Rgb(0.0f);
  BsdfEval be = bsdf_eval_pdf(bsdf_o, so.uv, so.wi, so.sh_frame.to_local(eo.d));
  if (be.value.is_black()) return Rgb(0.0f);
  ++counters.rays;
  if (scene.occluded(shadow_ray(so, eo))) return Rgb(0.0f);
  const float w = eo.delta ? 1.0f : mis_power(eo.pdf, be.pdf);
  return beta * be.value * eo.weight * w;
}

Rgb offset_emission(const FrameScene& scene, Vec3f from, const SurfaceInteraction& hit, Rgb beta, float pdf,
                    bool delta) {
  if (scene.emitter_of_shape(hit.shape) < 0) return Rgb(0.0f);
  const Rgb le = scene.eval_area_emitter(hit);
  if (le.is_black()) return Rgb(0.0f);
  return beta * le * (delta ? 1.0f : mis_power(pdf, scene.pdf_emitter_direction(from, hit)));
}

}  // namespace gdvr
