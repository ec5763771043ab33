// The cached base path of cached-path shifting (docs/gpt.md, "Cached-path
// Russian roulette"): every
// vertex with its sampling decisions, pdfs and the random numbers that made
// them, plus the base path's MIS-weighted contribution per technique. Offsets
// are built from this record alone (no second look at the sampler), and an
// offset can write its own record so that the shift can be applied backwards
// (the invertibility test).
#pragma once

#include <vector>

#include "core/bsdf/bsdf.h"
#include "core/render/frame_scene.h"

namespace gdvr {

// What follows vertex x_k on the path.
enum class PathNext : uint8_t {
  kEnd,      // no bounce: max_depth reached, delta-only sampling failed, zero weight
  kKilled,   // bounced, then Russian roulette ended the path
  kSurface,  // bounced and hit x_{k+1} (the next PathVertex)
  kEscaped,  // bounced and left the scene (environment emission, then the path ends)
};

struct PathVertex {
  SurfaceInteraction si;  // x_k (k >= 1; x_0 is the camera)
  int bsdf = -1;          // scene.bsdfs index
  Rgb beta;               // throughput arriving at x_k: f/p of the prefix, including RR divisions

  // ---- Emission at x_k (technique: BSDF sampling at x_{k-1}); k = 1 is `direct` ----
  Rgb le;                 // radiance emitted towards x_{k-1}
  float emitter_pdf = 0;  // solid-angle pdf emitter sampling at x_{k-1} would give x_k
  float w_emit = 0;       // base MIS weight (power heuristic against emitter sampling)
  Rgb emission;           // beta * le * w_emit: the base contribution of this technique

  // ---- Emitter sampling at x_k ----
  bool has_nee = false;   // false for delta-only BSDFs and past max_depth
  float u_select = 0;
  Vec2f u_light;
  EmitterSample es;
  bool nee_visible = false;
  Rgb nee_f;              // f(wo, wl) |cos| at x_k
  float w_nee = 0;        // base MIS weight
  Rgb nee;                // beta * nee_f * es.weight * w_nee (0 when occluded)
  // The light sample carries radiance but the base's BSDF value towards it
  // was zero, so the base traced no shadow ray: nee_visible says nothing. An
  // offset that reaches x_k along another direction may see a nonzero value
  // and must then test the ray itself.
  bool shadow_untested() const { return has_nee && !es.weight.is_black() && nee_f.is_black(); }

  // ---- BSDF sampling at x_k ----
  PathNext next = PathNext::kEnd;
  float u_lobe = 0;
  Vec2f u_dir;
  BsdfSample bs;          // wi in x_k's shading frame; pdf as sampled (non-Dirac: solid angle)
  float rr_q = 1.0f;      // survival probability applied after this bounce (1: no roulette)

  // ---- Environment emission when next == kEscaped ----
  Vec3f escape_dir;
  Rgb escape_le;
  float escape_pdf = 0;   // environment sampling pdf of escape_dir
  float w_escape = 0;
  Rgb escape;             // base contribution

  // The base's solid-angle pdf of x_k -> x_{k+1} evaluated from the recorded
  // positions, which the spatial reconnection shift needs for its MIS ratio
  // (< 0: not computed yet). The four offsets of a base path usually reconnect
  // at the same vertex, so the first computes it and the others reuse it; a
  // record belongs to one tracer, so the cache is never shared across threads.
  mutable float reconnect_pdf = -1.0f;
  // No technique from x_k on can contribute, for the base or for an offset
  // reconnected into x_k: no visible light sample at x_k or after it, no
  // emission at x_{k+1} or after it, no environment radiance where the path
  // escapes (set by trace_base_path). Two things depend on the offset's
  // direction into x_k and are not included: x_k's own emission, and an
  // untested light sample at x_k (shadow_untested). A shift that would
  // reconnect into such a vertex, having checked those two, can skip its
  // visibility ray: whatever it finds, every later technique adds w (0 - 0).
  bool dark_suffix = false;
};

struct PathRecord {
  Ray camera_ray;
  std::vector<PathVertex> v;  // v[0] = x_1, the first hit; empty if the camera ray escaped
  Rgb direct;                 // emitters seen directly from the camera (kept out of the solve)
  Rgb indirect;               // everything else: the part the gradients are about
  bool invalid = false;       // non-finite radiance: the sample is dropped

  void clear() {
    v.clear();
    direct = indirect = Rgb(0.0f);
    invalid = false;
  }
};

}  // namespace gdvr
