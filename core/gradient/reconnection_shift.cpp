#include "core/gradient/reconnection_shift.h"

#include "core/gradient/follow_base.h"
#include "core/math/sampling.h"

namespace gdvr {
namespace {

enum class OffsetState { kNotReconnected, kJustReconnected, kReconnected };

class CachedShift {
 public:
  CachedShift(const FrameScene& scene, const GptSettings& settings, const PathRecord& base, bool replay_prefix,
              PathCounters& counters, ShiftTrace* trace)
      : scene_(scene), desc_(scene.scene()), settings_(settings), base_(base), replay_prefix_(replay_prefix),
        counters_(counters), trace_(trace), acc_(base, settings.mis_epsilon, trace ? &trace->ratios : nullptr) {}

  ShiftResult run(const CameraHit& offset_first);

 private:
  // What the base does after vertex i; every stage below reads it.
  struct BaseBounce {
    bool escaped;            // the base's ray from x_k left the scene
    const PathVertex* next;  // x_{k+1} (null where escaped)
    Rgb c_b_next;            // the base's contribution found there (emission or the environment)
    float inv_q;             // 1 / the base's roulette survival, which applies to the offset too (§8)
  };
  // The stages of one vertex, by offset state. Each returns whether the
  // offset path goes on to the next vertex; where it does not, acc_ holds
  // everything (a failure has been recorded with fail_from).
  void emitter_technique(const PathVertex& v, const Bsdf& bsdf_b, const Bsdf& bsdf_o);
  bool along_reconnected(const PathVertex& v, const BaseBounce& b);
  bool leave_shared_vertex(size_t i, const PathVertex& v, const Bsdf& bsdf_b, const BaseBounce& b);
  bool reconnect(size_t i, const PathVertex& v, const Bsdf& bsdf_b, const Bsdf& bsdf_o, const BaseBounce& b);
  bool follow(size_t i, const PathVertex& v, const Bsdf& bsdf_o, bool both_diffuse, const BaseBounce& b);

  const Bsdf& bsdf_at(const SurfaceInteraction& si) const {
    return desc_.bsdfs[size_t(desc_.shapes[size_t(si.shape)].bsdf)];
  }
  // Vertex classes (Kettunen et al. 2015, by the lobe the base sampled): a
  // vertex the base left through a Dirac lobe is specular; otherwise it is as
  // rough as the BSDF's smoothest non-Dirac lobe. A smooth plastic whose
  // diffuse base was sampled is diffuse and can reconnect.
  // The hybrid shift keeps classifying whole BSDFs: its replayed prefix may
  // pick another lobe at x'_k than the base did at x_k, and the reverse shift
  // would then classify that vertex differently (not invertible).
  bool diffuse_for(const Bsdf& b, const BsdfSample& sampled) const {
    if (replay_prefix_) return b.roughness() > settings_.diffuse_roughness;
    return !sampled.is_delta() && bsdf_smooth_roughness(b) > settings_.diffuse_roughness;
  }
  // The vertex after the reconnection, x_{k+1} (or the offset's x'_{k+1} for
  // the invertibility test, which will copy the base's lobe there): diffuse if
  // its BSDF is, unless the base leaves it through a Dirac lobe, which a
  // changed incoming direction could not follow.
  bool diffuse_next(const Bsdf& b, const PathVertex& base_next) const {
    if (replay_prefix_) return b.roughness() > settings_.diffuse_roughness;
    const bool leaves = base_next.next == PathNext::kSurface || base_next.next == PathNext::kEscaped;
    return bsdf_smooth_roughness(b) > settings_.diffuse_roughness && !(leaves && base_next.bs.is_delta());
  }

  void technique(Rgb c_b, Rgb c_o, double ratio) { acc_.technique(c_b, c_o, ratio); }
  // Whether an offset arriving at the base vertex y along `dir` can get no
  // contribution from y on (PathVertex::dark_suffix), with the two parts that
  // depend on its direction checked here: y's own emission, and y's light
  // sample where the base's BSDF value was zero.
  bool dark_after_reconnecting(const PathVertex& y, Vec3f dir) const {
    if (!y.dark_suffix || scene_.emitter_of_shape(y.si.shape) >= 0) return false;
    if (!y.shadow_untested()) return true;
    const Bsdf& b = desc_.bsdfs[size_t(y.bsdf)];
    return bsdf_eval_pdf(b, y.si.uv, y.si.sh_frame.to_local(-dir), y.si.sh_frame.to_local(y.es.d)).value.is_black();
  }
  // The base vertex's light sample, visible from it (the shadow ray the base skipped).
  bool light_visible_from(const PathVertex& v) {
    ++counters_.rays;
    return !scene_.occluded(shadow_ray(v.si, v.es));
  }
  void fail_from(size_t i, bool with_nee) { acc_.fail_from(i, with_nee); }
  PathVertex* record(const SurfaceInteraction& si, const PathVertex& base_vertex) {
    if (!trace_) return nullptr;
    trace_->offset.v.push_back(base_vertex);
    PathVertex& o = trace_->offset.v.back();
    o.si = si;
    o.reconnect_pdf = -1.0f;  // the base's cache: not valid at the offset's positions
    o.bsdf = desc_.shapes[size_t(si.shape)].bsdf;
    o.has_nee = base_vertex.has_nee && !bsdf_at(si).is_delta_only();
    return &o;
  }

  const FrameScene& scene_;
  const Scene& desc_;
  const GptSettings& settings_;
  const PathRecord& base_;
  const bool replay_prefix_;
  PathCounters& counters_;
  ShiftTrace* trace_;
  ShiftAccumulator acc_;

  // The offset path so far.
  SurfaceInteraction so_;  // x'_k
  OffsetState state_ = OffsetState::kNotReconnected;
  Rgb beta_ = Rgb(1.0f);  // f(T x)|J| / p(x) of the offset prefix
  double ratio_ = 1.0;    // p(T x)|J| / p(x) of the prefix, per vertex in double (§8)
  Vec3f wo_reconnected_;  // kJustReconnected: the offset's incoming direction at the shared vertex (local)
  PathVertex* rec_ = nullptr;  // the offset's record of x'_k (traced runs only)
};

ShiftResult CachedShift::run(const CameraHit& offset_first) {
  const auto& verts = base_.v;
  if (trace_) {
    trace_->ratios.clear();
    trace_->offset.clear();
    trace_->offset.camera_ray = offset_first.ray;
  }
  if (verts.empty()) return acc_.result();  // the base saw only the environment: nothing but `direct`

  // ---- x'_1: the offset's camera ray (same sub-pixel position, Jacobian 1 on the film) ----
  if (!offset_first.hit) {
    fail_from(0, true);
    return acc_.result();
  }
  so_ = offset_first.si;
  rec_ = record(so_, verts[0]);

  for (size_t i = 0; i < verts.size(); ++i) {
    const PathVertex& v = verts[i];
    const Bsdf& bsdf_b = desc_.bsdfs[size_t(v.bsdf)];
    const bool shared = state_ != OffsetState::kNotReconnected;
    const Bsdf& bsdf_o = shared ? bsdf_b : bsdf_at(so_);
    if (v.has_nee) emitter_technique(v, bsdf_b, bsdf_o);
    if (v.next == PathNext::kEnd || v.next == PathNext::kKilled) break;

    BaseBounce b;
    b.escaped = v.next == PathNext::kEscaped;
    b.next = b.escaped ? nullptr : &verts[i + 1];
    b.c_b_next = b.escaped ? v.escape : b.next->emission;
    b.inv_q = 1.0f / v.rr_q;
    bool goes_on;
    if (state_ == OffsetState::kReconnected) {
      goes_on = along_reconnected(v, b);
    } else if (state_ == OffsetState::kJustReconnected) {
      goes_on = leave_shared_vertex(i, v, bsdf_b, b);
    } else {
      // Reconnect to x_{k+1} if x_k, x'_k and x_{k+1} are all diffuse.
      const bool diffuse_b = diffuse_for(bsdf_b, v.bs), diffuse_o = diffuse_for(bsdf_o, v.bs);
      const bool diffuse_y = b.escaped || diffuse_next(desc_.bsdfs[size_t(b.next->bsdf)], *b.next);
      goes_on = diffuse_b && diffuse_o && diffuse_y ? reconnect(i, v, bsdf_b, bsdf_o, b)
                                                    : follow(i, v, bsdf_o, diffuse_b && diffuse_o, b);
    }
    if (!goes_on) break;
  }
  return acc_.result();
}

// Emitter sampling at x'_k with the base's light sample.
void CachedShift::emitter_technique(const PathVertex& v, const Bsdf& bsdf_b, const Bsdf& bsdf_o) {
  Rgb c_o;
  double r = ratio_;
  if (state_ == OffsetState::kReconnected) {
    if (v.nee_visible) c_o = beta_ * v.nee_f * v.es.weight * v.w_nee;
  } else if (state_ == OffsetState::kJustReconnected) {
    // Same point, same light sample, same shadow ray; only the incoming
    // direction differs. Where the base's BSDF value was zero it traced no
    // shadow ray, and the offset's value need not be zero: it tests the ray.
    if ((v.nee_visible || v.shadow_untested()) && !v.es.weight.is_black()) {
      BsdfEval be = bsdf_eval_pdf(bsdf_b, v.si.uv, wo_reconnected_, v.si.sh_frame.to_local(v.es.d));
      if (!be.value.is_black() && (v.nee_visible || light_visible_from(v))) {
        float w = v.es.delta ? 1.0f : mis_power(v.es.pdf, be.pdf);
        c_o = beta_ * be.value * v.es.weight * w;
      }
    }
  } else {
    if (rec_ && !bsdf_o.is_delta_only()) rec_->es = scene_.sample_emitter_direction(so_, v.u_select, v.u_light);
    c_o = offset_emitter_sampling(scene_, so_, bsdf_o, v, beta_, &r, counters_, /* same_emitters = */ true);
  }
  technique(v.nee, c_o, r);
}

// Reconnected: the rest of the base path, same f and pdfs.
bool CachedShift::along_reconnected(const PathVertex& v, const BaseBounce& b) {
  beta_ *= v.bs.weight * b.inv_q;
  Rgb c_o = b.escaped ? beta_ * v.escape_le * v.w_escape : beta_ * b.next->le * b.next->w_emit;
  technique(b.c_b_next, c_o, ratio_);
  if (rec_ && b.next) rec_ = record(b.next->si, *b.next);
  return true;
}

// Just reconnected: the BSDF at the shared vertex x_k re-evaluated for the
// offset's incoming direction, towards the base's x_{k+1}.
bool CachedShift::leave_shared_vertex(size_t i, const PathVertex& v, const Bsdf& bsdf_b, const BaseBounce& b) {
  BsdfEval be = bsdf_eval_pdf(bsdf_b, v.si.uv, wo_reconnected_, v.bs.wi);
  if (!(be.pdf > 0) || be.value.is_black()) {
    fail_from(i, false);
    return false;
  }
  if (rec_) rec_->bs.pdf = be.pdf, rec_->bs.weight = be.value / be.pdf;
  beta_ *= be.value * (b.inv_q / v.bs.pdf);
  ratio_ *= double(be.pdf) / double(v.bs.pdf);
  Rgb c_o;
  if (b.escaped && !v.escape_le.is_black()) c_o = beta_ * v.escape_le * mis_power(be.pdf, v.escape_pdf);
  if (!b.escaped && !b.next->le.is_black()) c_o = beta_ * b.next->le * mis_power(be.pdf, b.next->emitter_pdf);
  technique(b.c_b_next, c_o, ratio_);
  state_ = OffsetState::kReconnected;
  if (rec_ && b.next) rec_ = record(b.next->si, *b.next);
  return true;
}

// x_k, x'_k and x_{k+1} are all diffuse: connect x'_k to the base's x_{k+1}
// (or its direction at infinity), which the offset then shares.
bool CachedShift::reconnect(size_t i, const PathVertex& v, const Bsdf& bsdf_b, const Bsdf& bsdf_o,
                            const BaseBounce& b) {
  const PathVertex* nv = b.next;
  Vec3f dir;
  float jacobian = 1.0f;
  Ray connect;
  if (b.escaped) {
    // A direction at infinity: copied, Jacobian 1; the offset must escape too.
    dir = v.escape_dir;
    connect = so_.spawn_ray(dir);
  } else {
    Vec3f d = nv->si.p - so_.p;
    float dist2 = length_squared(d);
    Vec3f d_base = nv->si.p - v.si.p;
    float dist2_base = length_squared(d_base);
    if (!(dist2 > 0) || !(dist2_base > 0)) {
      fail_from(i, false);
      return false;
    }
    float dist = std::sqrt(dist2);
    dir = d / dist;
    // |J| = (cos θ'_y / cos θ_y) (d² / d'²) at the reconnection vertex y = x_{k+1} (§3.1).
    float cos_o = std::abs(dot(nv->si.n, dir));
    float cos_b = std::abs(dot(nv->si.n, d_base)) / std::sqrt(dist2_base);
    if (!(cos_o > 1e-6f) || !(cos_b > 1e-6f)) {
      fail_from(i, false);
      return false;
    }
    jacobian = (cos_o / cos_b) * (dist2_base / dist2);
    connect = so_.spawn_ray_to(nv->si);
  }
  // Nothing after the reconnection can contribute, whatever its visibility
  // ray finds: the ray is not traced. Kept in traced runs, whose record
  // and ratios the invertibility tests read.
  if (!trace_ && (b.escaped ? v.escape_le.is_black() : dark_after_reconnecting(*nv, dir))) return false;
  ++counters_.rays;
  if (scene_.occluded(connect)) {
    fail_from(i, false);
    return false;
  }
  Vec3f wi_o = so_.sh_frame.to_local(dir);
  BsdfEval be = bsdf_eval_pdf(bsdf_o, so_.uv, so_.wi, wi_o);
  if (!(be.pdf > 0) || be.value.is_black() || !std::isfinite(jacobian)) {
    fail_from(i, false);
    return false;
  }
  beta_ *= be.value * (jacobian * b.inv_q / v.bs.pdf);
  // MIS: the base's pdf along x_k -> x_{k+1} from the positions, as the
  // offset's is (see temporal_reconnection_shift.cpp: the traced ray left
  // from a point offset along the normal).
  float pdf_b = v.bs.pdf;
  if (!b.escaped) {
    if (v.reconnect_pdf < 0) {
      const Vec3f d_base = nv->si.p - v.si.p;
      v.reconnect_pdf = bsdf_eval_pdf(bsdf_b, v.si.uv, v.si.wi, v.si.sh_frame.to_local(normalize(d_base))).pdf;
    }
    pdf_b = v.reconnect_pdf;
    if (!(pdf_b > 0)) {
      fail_from(i, false);
      return false;
    }
  }
  ratio_ *= double(be.pdf) * double(jacobian) / double(pdf_b);
  if (rec_) {
    rec_->bs = v.bs;
    rec_->bs.wi = wi_o, rec_->bs.pdf = be.pdf, rec_->bs.weight = be.value / be.pdf;
    rec_->escape_dir = dir;
  }
  Rgb c_o;
  if (b.escaped) {
    if (!v.escape_le.is_black()) c_o = beta_ * v.escape_le * mis_power(be.pdf, v.escape_pdf);
    technique(b.c_b_next, c_o, ratio_);
    return false;
  }
  // The shared vertex seen from x'_k: emission and its emitter-sampling pdf change.
  SurfaceInteraction y = nv->si;
  y.wi = y.sh_frame.to_local(-dir);
  if (scene_.emitter_of_shape(y.shape) >= 0) {
    Rgb le = scene_.eval_area_emitter(y);
    if (!le.is_black()) c_o = beta_ * le * mis_power(be.pdf, scene_.pdf_emitter_direction(so_.p, y));
  }
  technique(b.c_b_next, c_o, ratio_);
  state_ = OffsetState::kJustReconnected;
  wo_reconnected_ = y.wi;
  if (rec_) rec_ = record(y, *nv);
  return true;
}

// Not reconnecting here: follow the base's bounce from x'_k (replayed by the
// hybrid shift, half-vector copy by the reconnection shift) and trace it.
// `both_diffuse`: x_k and x'_k are, so the offset's next vertex must not be
// (the reverse shift would reconnect where this one did not).
bool CachedShift::follow(size_t i, const PathVertex& v, const Bsdf& bsdf_o, bool both_diffuse, const BaseBounce& b) {
  FollowedBounce fb;
  if (!follow_base_bounce(bsdf_o, so_, v, replay_prefix_, b.inv_q, &beta_, &ratio_, &fb)) {
    fail_from(i, false);
    return false;
  }
  const Vec3f wi_o = fb.wi;
  const float pdf_o = fb.pdf;
  const bool delta_o = fb.delta;
  if (rec_) rec_->bs = fb.sample;

  const Vec3f d_o = so_.sh_frame.to_world(wi_o);
  if (rec_) rec_->escape_dir = d_o;
  SurfaceInteraction sn;
  ++counters_.rays;
  const bool hit = scene_.intersect(so_.spawn_ray(d_o), &sn);
  if (hit == b.escaped) {  // surface against environment
    fail_from(i, false);
    return false;
  }
  if (!hit) {
    Rgb le = scene_.eval_environment(d_o), c_o;
    if (!le.is_black())
      c_o = beta_ * le * (delta_o ? 1.0f : mis_power(pdf_o, scene_.pdf_environment_direction(d_o)));
    technique(b.c_b_next, c_o, ratio_);
    return false;
  }
  // Invertibility (§2): the reverse shift, seeing x_k, x'_k and x'_{k+1} all
  // diffuse, would reconnect where this one did not.
  if (both_diffuse && diffuse_next(bsdf_at(sn), *b.next)) {
    fail_from(i, false);
    return false;
  }
  technique(b.c_b_next, offset_emission(scene_, so_.p, sn, beta_, pdf_o, delta_o), ratio_);
  so_ = sn;
  if (rec_) rec_ = record(so_, *b.next);
  return true;
}

}  // namespace

ShiftResult shift_from_cache(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                             const CameraHit& offset_first, bool replay_prefix, PathCounters& counters,
                             ShiftTrace* trace) {
  CachedShift shift(scene, settings, base, replay_prefix, counters, trace);
  return shift.run(offset_first);
}

}  // namespace gdvr
