#include "core/gradient/temporal_reconnection_shift.h"

#include <cmath>

#include "core/gradient/follow_base.h"
#include "core/math/sampling.h"

namespace gdvr {
namespace {

class TemporalShift {
 public:
  TemporalShift(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                const TemporalShiftTarget& target, PathCounters& counters, ShiftTrace* trace)
      : desc_(scene.scene()),
        other_(*target.scene),
        camera_(*target.camera),
        motion_(*target.motion),
        settings_(settings),
        base_(base),
        counters_(counters),
        trace_(trace),
        acc_(base, settings.mis_epsilon, trace ? &trace->ratios : nullptr) {}

  ShiftResult run(Vec2f film);

 private:
  const Bsdf& bsdf_of(const SurfaceInteraction& si) const {
    const Scene& d = other_.scene();
    return d.bsdfs[size_t(d.shapes[size_t(si.shape)].bsdf)];
  }
  // Vertex classes by the lobe the base sampled, as the spatial reconnection
  // shift (reconnection_shift.cpp; Kettunen et al. 2015): a vertex the base
  // left through a Dirac lobe is specular, otherwise it is as rough as its
  // BSDF's smoothest non-Dirac lobe, so smooth plastic reconnects at its
  // diffuse base. `sampled`: the base's sample at x_k (also used for y_k,
  // which copies that lobe).
  bool diffuse_for(const Bsdf& b, const BsdfSample& sampled) const {
    return !sampled.is_delta() && bsdf_smooth_roughness(b) > settings_.diffuse_roughness;
  }
  // The vertex after the reconnection (x_{k+1}, or the offset's y_{k+1} for
  // the invertibility test): diffuse if its BSDF is, unless the base leaves it
  // through a Dirac lobe, which a changed incoming direction could not follow.
  bool diffuse_next(const Bsdf& b, const PathVertex& base_next) const {
    const bool leaves = base_next.next == PathNext::kSurface || base_next.next == PathNext::kEscaped;
    return bsdf_smooth_roughness(b) > settings_.diffuse_roughness && !(leaves && base_next.bs.is_delta());
  }
  // The segment from `from` to `to` is free in frame t' (a ray between the
  // two offset end points, spawn_ray_to: a ray offset parallel to the segment
  // is blocked by `to`'s own triangle when it arrives at an angle).
  // `static_base_segment`: it is a segment of the base path (free in frame t)
  // between two shapes that do not move, so only animated shapes can block it
  // now; testing the static ones again would only add self-intersection noise.
  bool unoccluded(const SurfaceInteraction& from, const SurfaceInteraction& to, bool static_base_segment) {
    const Ray r = from.spawn_ray_to(to);
    ++counters_.rays;
    return static_base_segment ? !other_.occluded_by_animated(r) : !other_.occluded(r);
  }
  bool escapes(const SurfaceInteraction& from, Vec3f dir) {
    ++counters_.rays;
    return !other_.occluded(from.spawn_ray(dir));
  }
  const ShiftResult& fail(size_t i) {
    acc_.fail_from(i, /* with_nee = */ false);
    return acc_.result();
  }
  // ---- The offset as a record (tests: the backward shift) ----
  PathVertex* record(const SurfaceInteraction& si, const PathVertex& base_vertex) {
    if (!trace_) return nullptr;
    trace_->offset.v.push_back(base_vertex);
    PathVertex& o = trace_->offset.v.back();
    o.si = si;
    o.bsdf = other_.scene().shapes[size_t(si.shape)].bsdf;
    o.has_nee = base_vertex.has_nee && !bsdf_of(si).is_delta_only();
    if (o.has_nee) o.es = other_.sample_emitter_direction(si, o.u_select, o.u_light);
    return &o;
  }
  // The offset's bounce: the base's, with the offset's direction and pdf.
  static void record_bounce(PathVertex* rec, const PathVertex& v, Vec3f wi, const BsdfEval& be, Vec3f world_dir) {
    if (!rec) return;
    rec->bs = v.bs;
    rec->bs.wi = wi, rec->bs.pdf = be.pdf, rec->bs.weight = be.value / be.pdf;
    rec->escape_dir = world_dir;
  }

  const Scene& desc_;
  const FrameScene& other_;
  const PerspectiveCamera& camera_;
  const ShapeMotion& motion_;
  const GptSettings& settings_;
  const PathRecord& base_;
  PathCounters& counters_;
  ShiftTrace* trace_;
  ShiftAccumulator acc_;
};

ShiftResult TemporalShift::run(Vec2f film) {
  const auto& verts = base_.v;
  if (verts.empty()) return acc_.result();  // the base saw only the environment: nothing but `direct`

  // ---- y_1: frame t''s camera through the same film position (Jacobian 1 on the film) ----
  const Ray camera_ray = camera_.generate_ray(film);
  if (trace_) {
    trace_->ratios.clear();
    trace_->offset.clear();
    trace_->offset.camera_ray = camera_ray;
  }
  SurfaceInteraction so;
  ++counters_.rays;
  if (!other_.intersect_camera_ray(camera_ray, &so)) {
    acc_.fail_from(0, /* with_nee = */ true);
    return acc_.result();
  }
  PathVertex* rec = record(so, verts[0]);
  bool carried = false;   // so = M(x_k): the offset has reconnected
  bool rigid_in = false;  // ... and was entered along the base's incoming direction, carried by x_k's motion
  Rgb beta(1.0f);         // f(T x)|J| / p(x) of the offset prefix
  double ratio = 1.0;     // p(T x)|J| / p(x), per vertex in double (§8)

  for (size_t i = 0; i < verts.size(); ++i) {
    const PathVertex& v = verts[i];
    const Bsdf& bsdf_b = desc_.bsdfs[size_t(v.bsdf)];
    const Bsdf& bsdf_o = bsdf_of(so);

    // ---- Emitter sampling at y_k with the base's light sample, in frame t' ----
    if (v.has_nee) {
      double r = ratio;
      const Rgb c_o = offset_emitter_sampling(other_, so, bsdf_o, v, beta, &r, counters_, /* same_emitters = */ false);
      acc_.technique(v.nee, c_o, r);
    }
    if (v.next == PathNext::kEnd || v.next == PathNext::kKilled) break;

    const bool escaped = v.next == PathNext::kEscaped;
    const PathVertex* nv = escaped ? nullptr : &verts[i + 1];
    const Rgb c_b_next = escaped ? v.escape : nv->emission;
    const float inv_q = 1.0f / v.rr_q;  // the base's roulette decision applies to the offset (§8)

    // ---- Prefix: follow the base until x_k, y_k and x_{k+1} are all diffuse ----
    if (!carried) {
      const bool diffuse_b = diffuse_for(bsdf_b, v.bs), diffuse_o = diffuse_for(bsdf_o, v.bs);
      const bool diffuse_y = escaped || diffuse_next(desc_.bsdfs[size_t(nv->bsdf)], *nv);
      if (!(diffuse_b && diffuse_o && diffuse_y)) {
        FollowedBounce fb;
        if (!follow_base_bounce(bsdf_o, so, v, /* replay = */ false, inv_q, &beta, &ratio, &fb)) return fail(i);
        const Vec3f d_o = so.sh_frame.to_world(fb.wi);
        if (rec) rec->bs = fb.sample, rec->escape_dir = d_o;
        SurfaceInteraction sn;
        ++counters_.rays;
        const bool hit = other_.intersect(so.spawn_ray(d_o), &sn);
        if (hit == escaped) return fail(i);  // surface against environment
        if (!hit) {
          const Rgb le = other_.eval_environment(d_o);
          Rgb c_o;
          if (!le.is_black())
            c_o = beta * le * (fb.delta ? 1.0f : mis_power(fb.pdf, other_.pdf_environment_direction(d_o)));
          acc_.technique(c_b_next, c_o, ratio);
          break;
        }
        // Invertibility (§2): the reverse shift, seeing x_k, y_k and y_{k+1}
        // all diffuse, would reconnect where this one did not.
        if (diffuse_b && diffuse_o && diffuse_next(bsdf_of(sn), *nv)) return fail(i);
        acc_.technique(c_b_next, offset_emission(other_, so.p, sn, beta, fb.pdf, fb.delta), ratio);
        so = sn;
        rec = record(so, *nv);
        continue;
      }
    }

    // ---- To the base's next vertex, carried: the reconnection, then every later segment ----
    // y_k is the base's own vertex: carried without moving, or traced to
    // exactly the base's point (a static camera sees the same first hit).
    const bool at_base_vertex =
        !motion_.moves(v.si.shape) &&
        (carried || (so.shape == v.si.shape && so.p.x == v.si.p.x && so.p.y == v.si.p.y && so.p.z == v.si.p.z));
    // ... entered along the base's incoming direction, carried by its motion.
    const bool entered_rigidly =
        carried ? rigid_in : at_base_vertex && so.wi.x == v.si.wi.x && so.wi.y == v.si.wi.y && so.wi.z == v.si.wi.z;
    // Rigid: both ends move together and y_k was entered rigidly, so
    // directions, lengths, f and pdfs are the base's.
    const bool rigid =
        entered_rigidly && (escaped ? !motion_.moves(v.si.shape) : motion_.same(v.si.shape, nv->si.shape));
    if (!rigid && v.bs.is_delta()) return fail(i);  // a Dirac lobe cannot take a changed direction

    if (escaped) {
      // A direction at infinity: copied (Jacobian 1); the offset must escape in frame t' too.
      const Vec3f dir = v.escape_dir;
      if (!escapes(so, dir)) return fail(i);
      const Rgb le = other_.eval_environment(dir);
      Rgb c_o;
      if (rigid) {
        beta *= v.bs.weight * inv_q;
        if (!le.is_black())
          c_o = beta * le * (v.bs.is_delta() ? 1.0f : mis_power(v.bs.pdf, other_.pdf_environment_direction(dir)));
        if (rec) rec->bs = v.bs, rec->escape_dir = dir;
      } else {
        const BsdfEval be = bsdf_eval_pdf(bsdf_o, so.uv, so.wi, so.sh_frame.to_local(dir));
        if (!(be.pdf > 0) || be.value.is_black()) return fail(i);
        record_bounce(rec, v, so.sh_frame.to_local(dir), be, dir);
        beta *= be.value * (inv_q / v.bs.pdf);
        ratio *= double(be.pdf) / double(v.bs.pdf);
        if (!le.is_black()) c_o = beta * le * mis_power(be.pdf, other_.pdf_environment_direction(dir));
      }
      acc_.technique(c_b_next, c_o, ratio);
      break;
    }

    SurfaceInteraction y = motion_.carry(nv->si);
    const Vec3f d = y.p - so.p;
    const float dist2 = length_squared(d);
    if (!(dist2 > 0)) return fail(i);
    const float dist = std::sqrt(dist2);
    const Vec3f dir = d / dist;
    // The base's own segment x_k -> x_{k+1} (y_k = x_k, y_{k+1} = x_{k+1}).
    const bool static_base_segment = at_base_vertex && !motion_.moves(nv->si.shape);
    if (!unoccluded(so, y, static_base_segment)) return fail(i);
    Rgb c_o;
    if (rigid) {
      beta *= v.bs.weight * inv_q;
      if (motion_.moves(y.shape)) y.wi = y.sh_frame.to_local(-dir);  // else y = x_{k+1} exactly, wi included
      c_o = beta * nv->le * nv->w_emit;                              // same emission, same MIS weight
      if (rec) {
        rec->bs = v.bs, rec->escape_dir = dir;
        if (motion_.moves(v.si.shape)) rec->bs.wi = so.sh_frame.to_local(dir);
      }
    } else {
      // |J| = (cos θ'_y / cos θ_y)(d² / d'²) at y = M(x_{k+1}) (§3.1), times
      // the area change of the motion (1 if rigid).
      const Vec3f d_base = nv->si.p - v.si.p;
      const float dist2_base = length_squared(d_base);
      const float cos_o = std::abs(dot(y.n, dir));
      const float cos_b = dist2_base > 0 ? std::abs(dot(nv->si.n, d_base)) / std::sqrt(dist2_base) : 0.0f;
      if (!(cos_o > 1e-6f) || !(cos_b > 1e-6f)) return fail(i);
      const float jacobian = (cos_o / cos_b) * (dist2_base / dist2) * motion_.area_jacobian(nv->si);
      const BsdfEval be = bsdf_eval_pdf(bsdf_o, so.uv, so.wi, so.sh_frame.to_local(dir));
      if (!(be.pdf > 0) || be.value.is_black() || !std::isfinite(jacobian)) return fail(i);
      beta *= be.value * (jacobian * inv_q / v.bs.pdf);
      // The MIS ratio takes the base's pdf along x_k -> x_{k+1} from the
      // positions, as the offset's is (and as the reverse shift will see
      // both): the traced ray left from x_k offset along the normal (Mitsuba's
      // epsilon, 0.05 units at a scale of 500), which tilts a short segment
      // by a few 1e-3 rad and would put |w + w' − 1| at ~1e-2. The
      // contribution keeps the sampled pdf, the base estimator's own.
      const float pdf_b =
          bsdf_eval_pdf(bsdf_b, v.si.uv, v.si.wi, v.si.sh_frame.to_local(d_base / std::sqrt(dist2_base))).pdf;
      if (!(pdf_b > 0)) return fail(i);
      ratio *= double(be.pdf) * double(jacobian) / double(pdf_b);
      y.wi = y.sh_frame.to_local(-dir);
      record_bounce(rec, v, so.sh_frame.to_local(dir), be, dir);
      c_o = offset_emission(other_, so.p, y, beta, be.pdf, /* delta = */ false);
    }
    acc_.technique(c_b_next, c_o, ratio);
    // y_{k+1} was entered along the carried base segment iff y_k was carried
    // (or is the base's vertex) with the same motion as x_{k+1}.
    rigid_in = (carried || at_base_vertex) && motion_.same(v.si.shape, nv->si.shape);
    carried = true;
    so = y;
    rec = record(so, *nv);
  }
  return acc_.result();
}

}  // namespace

ShiftResult temporal_reconnection_shift(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                                        Vec2f film, const TemporalShiftTarget& target, PathCounters& counters,
                                        ShiftTrace* trace) {
  TemporalShift shift(scene, settings, base, target, counters, trace);
  return shift.run(film);
}

}  // namespace gdvr
