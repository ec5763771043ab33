// The offset's bounce at a vertex where it does not reconnect (Kettunen et al.
// 2015; docs/gpt.md, "Shift mappings"): replay the base's random numbers
// (hybrid shift), take the same Dirac lobe, or copy the half vector of a
// glossy bounce. Shared by the spatial cached shifts and the temporal
// path-space shift.
#pragma once

#include "core/bsdf/bsdf.h"
#include "core/gradient/path_record.h"
#include "core/render/path_tracer.h"

namespace gdvr {

struct FollowedBounce {
  Vec3f wi;       // the offset's new direction (its local shading frame)
  float pdf = 0;  // the offset's own pdf of it (solid angle; Dirac: lobe probability)
  bool delta = false;
  BsdfSample sample;  // the bounce as a BsdfSample (for offset records)
};

// `v`: the base vertex x_k, `so`: the offset vertex x'_k with BSDF `bsdf_o`.
// Multiplies *beta by the offset's f/p in the base's measure (Jacobian and
// 1/rr_q included) and *ratio by p(T x)|J|/p(x) of the bounce. False: the
// shift fails here (no such lobe, degenerate half vector, TIR, zero pdf).
bool follow_base_bounce(const Bsdf& bsdf_o, const SurfaceInteraction& so, const PathVertex& v, bool replay, float inv_q,
                        Rgb* beta, double* ratio, FollowedBounce* out);

// Emitter sampling at the offset vertex `so` with the base vertex's light
// sample (its random numbers), in `scene` (the offset's frame). Returns the
// offset's contribution f(T x)/p(x); sets *ratio to 0 where the offset cannot
// generate the technique (delta-only BSDF, zero light pdf), else leaves it.
// `same_emitters`: `scene` has the base's emitters (a spatial shift), so a
// sample of an infinitely distant emitter (environment, directional light),
// which does not depend on the shading point, is the base's and is reused.
Rgb offset_emitter_sampling(const FrameScene& scene, const SurfaceInteraction& so, const Bsdf& bsdf_o,
                            const PathVertex& v, Rgb beta, double* ratio, PathCounters& counters, bool same_emitters);

// Emission of `hit` seen from `from` along a bounce with (solid-angle) pdf
// `pdf`, MIS-weighted against emitter sampling from `from` (1 after a Dirac bounce).
Rgb offset_emission(const FrameScene& scene, Vec3f from, const SurfaceInteraction& hit, Rgb beta, float pdf,
                    bool delta);

}  // namespace gdvr
