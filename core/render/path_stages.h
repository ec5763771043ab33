// The path tracer's work per vertex, cut at its two ray casts so that a path
// can wait between them. trace_path() runs one path through these stages;
// trace_path_batch() (path_batch.h) runs a batch of paths stage by stage, so
// that many independent paths' shading sits between two ray casts. Both call
// the same functions, so a path's radiance is the same bit for bit whichever
// driver ran it (but where its camera ray meets two triangles at exactly the
// same t: RayCoherence in accelerator.h).
//
// Per vertex:
//   [closest hit] -> add_emission -> sample_emitter -> connect_emitter
//                 -> sample_bsdf -> [shadow ray] -> resolve_shadow
// The emitter's contribution waits in the state until its shadow ray is
// answered. The last ray under max_depth looks for emitters first (see
// cast_last below). The stages draw the path's numbers in the order
// Mitsuba 3's `path` integrator does, which the gradient-domain base path
// (core/gradient/base_path.h) replays.
#pragma once

#include <limits>

#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/render/frame_scene.h"
#include "core/render/path_tracer.h"
#include "core/render/russian_roulette.h"

namespace gdvr {

// Paths in flight per thread in path_batch.h's batches, and the most rays
// the stream casts below take at once. The states (~300 bytes each; the
// vector batch's ~200) stay in L2. 256 rather than 64: a batch's paths end at
// different depths, so its later streams thin out, and every stream and
// kernel pass has a fixed cost; with four times the paths per batch, the
// camera rays go to Embree as one coherent stream of 256 and the tail of
// thin streams is paid once per 256 paths. Paired one-thread renders against
// 64: 1.063x on cbox, 1.036x on veach-mis, 1.053x on matpreview (512: 1.049,
// 1.022, 1.067). Refilling the lanes of a 64-path batch as its paths end
// (path regeneration) was slower, 0.95x: the few fresh camera rays of each
// pass lose what a coherent stream of camera rays gains.
constexpr int kPathBatch = 256;

struct PathState {
  Sampler sampler;
  Ray ray;  // the ray to trace next
  Rgb throughput{1.0f}, result{0.0f}, direct{0.0f};
  float eta = 1.0f;
  int depth = 0;
  // The previous vertex, for MIS when a BSDF-sampled ray hits an emitter.
  Vec3f prev_p;
  float prev_bsdf_pdf = 1.0f;
  bool prev_bsdf_delta = true;

  bool hit = false;       // what the closest-hit query of `ray` returned
  // Set by a last ray (cast_last): something that emits nothing lies before
  // the emitter or environment that `hit` and `ray` point at, so nothing is
  // seen. False until then (start_path), and no other cast writes it.
  bool blocked = false;
  SurfaceInteraction si;  // the vertex it found
  const Bsdf* bsdf = nullptr;  // its BSDF
  bool continues = true;  // false once the path has no next ray
  // Some vertex has scattered the path other than straight through (a thin
  // dielectric's transmission is straight through). In a scene that hides its
  // emitters, a path that never scattered saw what it saw directly, and
  // counts nothing (finish_path), as Mitsuba 3's "valid ray" rule has it: the
  // environment behind a window pane stays hidden.
  bool scattered = false;

  EmitterSample emitter;  // next-event estimation's sample at si
  float u_lobe = 0;       // BSDF sampling's numbers (draw_bsdf_numbers)
  Vec2f u_dir;

  // Next-event estimation waiting for its shadow ray.
  bool shadow_pending = false;
  Ray shadow;
  Rgb shadow_contribution;
};

// Sets what a new path reads before writing (not the whole state: hit, si,
// bsdf and emitter are written by the stages before they are read).
inline void start_path(PathState* st, const Ray& camera_ray, const Sampler& sampler) {
  st->sampler = sampler;
  st->ray = camera_ray;
  st->throughput = Rgb(1.0f);
  st->result = Rgb(0.0f);
  st->direct = Rgb(0.0f);
  st->eta = 1.0f;
  st->depth = 0;
  st->prev_p = camera_ray.o;
  st->prev_bsdf_pdf = 1.0f;
  st->prev_bsdf_delta = true;
  st->continues = true;
  st->scattered = false;
  st->blocked = false;
  st->shadow_pending = false;
}

// Before `ray` is cast: the emitter sample at the vertex it finds draws the
// next three numbers; an environment map's tables miss the cache, so their
// loads start now and overlap the traversal (frame_scene.h).
inline void prefetch_for_next_vertex(const FrameScene& scene, const PathState& st) {
  scene.prefetch_next_emitter_sample(st.sampler);
}

// The depth of a path's last vertex under max_depth (path_depth_limit).
// There only emission seen along the ray counts; nothing is sampled.
inline int last_vertex_depth(const PathTracerSettings& settings) { return path_depth_limit(settings) - 1; }

// ---- After the closest-hit query (st->hit, st->si) ----

// Emission seen along the ray, weighted against emitter sampling. Sets
// st->continues: whether the path goes on from this vertex.
inline void add_emission(const FrameScene& scene, const PathTracerSettings& settings, PathState* st) {
  const SurfaceInteraction& si = st->si;
  if (!(st->depth == 0 && settings.hide_emitters) && !st->blocked) {
    Rgb emitted;
    float emitter_pdf = 0;
    if (!st->hit) {
      const FrameScene::EnvironmentLookup env = scene.environment_along(st->ray.d);
      emitted = env.radiance;
      emitter_pdf = env.pdf;
    } else if (scene.emitter_of_shape(si.shape) >= 0) {
      emitted = scene.eval_area_emitter(si);
      if (!st->prev_bsdf_delta && !emitted.is_black()) emitter_pdf = scene.pdf_emitter_direction(st->prev_p, si);
    }
    if (!emitted.is_black()) {
      float w = st->prev_bsdf_delta ? 1.0f : mis_power(st->prev_bsdf_pdf, emitter_pdf);
      Rgb contrib = st->throughput * emitted * w;
      st->result += contrib;
      if (st->depth == 0) st->direct += contrib;
    }
  }
  st->continues = st->hit && st->depth < last_vertex_depth(settings);
  if (st->continues) {
    const Scene& desc = scene.scene();
    st->bsdf = &desc.bsdfs[size_t(desc.shapes[size_t(si.shape)].bsdf)];
  }
}

// Emitter sampling (skipped for purely specular BSDFs): the sample waits in
// st->emitter for connect_emitter.
inline void sample_emitter(const FrameScene& scene, PathState* st) {
  st->emitter = EmitterSample{};
  if (st->bsdf->is_delta_only()) return;
  float u_select = st->sampler.next_1d();
  Vec2f u_light = st->sampler.next_2d();
  st->emitter = scene.sample_emitter_direction(st->si, u_select, u_light);
}

// The BSDF towards the emitter sample, MIS-weighted; a contribution that is
// not zero waits for its shadow ray (st->shadow_pending).
inline void connect_emitter(PathState* st) {
  const EmitterSample& es = st->emitter;
  if (es.weight.is_black()) return;
  const SurfaceInteraction& si = st->si;
  Vec3f wi_local = si.sh_frame.to_local(es.d);
  BsdfEval be = bsdf_eval_pdf(*st->bsdf, si.uv, si.wi, wi_local);
  const Rgb& f = be.value;
  if (f.is_black()) return;
  float w = es.delta ? 1.0f : mis_power(es.pdf, be.pdf);
  st->shadow = shadow_ray(si, es);
  st->shadow_contribution = st->throughput * f * es.weight * w;
  st->shadow_pending = true;
}

// BSDF sampling's two numbers, the first the stage draws.
inline void draw_bsdf_numbers(PathState* st) {
  st->u_lobe = st->sampler.next_1d();
  st->u_dir = st->sampler.next_2d();
}

// BSDF sampling from the numbers drawn, the next ray and Russian roulette.
// Sets st->continues. `slope11`: where bsdf_start_slope_inversion started an
// inversion for this sample, its slope (a batch runs them side by side:
// path_batch.cpp), else null.
inline void sample_bsdf_drawn(const PathTracerSettings& settings, PathState* st, const Vec2f* slope11) {
  const SurfaceInteraction& si = st->si;
  st->continues = false;
  BsdfSample bs;
  // bsdf_sample() returns only finite weights, pdfs and directions.
  const bool sampled = slope11 ? bsdf_sample_from_slope(*st->bsdf, si.uv, si.wi, st->u_lobe, *slope11, &bs)
                               : bsdf_sample(*st->bsdf, si.uv, si.wi, st->u_lobe, st->u_dir, &bs);
  st->scattered = st->scattered || !(sampled && passes_straight_through(*st->bsdf, bs));
  if (!sampled || bs.weight.is_black()) return;
  st->throughput *= bs.weight;
  st->eta *= bs.eta;
  Vec3f d = si.sh_frame.to_world(bs.wi);
  st->ray = si.spawn_ray(d);
  st->prev_p = si.p;
  st->prev_bsdf_pdf = bs.pdf;
  st->prev_bsdf_delta = bs.is_delta();

  // ---- Russian roulette (russian_roulette.h; counted after the bounce) ----
  float throughput_max = max_component(st->throughput);
  if (!(throughput_max > 0)) return;
  if (st->depth + 1 >= settings.rr_depth) {
    float q = russian_roulette_survival(throughput_max, st->eta);
    if (st->sampler.next_1d() >= q) return;
    st->throughput *= 1.0f / q;
  }
  ++st->depth;
  st->continues = true;
}

// BSDF sampling, the next ray and Russian roulette. Sets st->continues.
inline void sample_bsdf(const PathTracerSettings& settings, PathState* st) {
  draw_bsdf_numbers(st);
  sample_bsdf_drawn(settings, st, nullptr);
}

// The answer to st->shadow.
inline void resolve_shadow(bool occluded, PathState* st) {
  if (!occluded) st->result += st->shadow_contribution;
  st->shadow_pending = false;
}

// A finished path's sample from its sums; a sum that is not finite is
// counted and the sample dropped (zero).
inline PathSample finish_path(const Rgb& result, const Rgb& direct, PathCounters& counters) {
  if (!is_finite(result)) {
    ++counters.invalid_samples;
    return PathSample{};
  }
  PathSample out;
  out.radiance = result;
  out.direct = direct;
  return out;
}
inline PathSample finish_path(const FrameScene& scene, const PathState& st, PathCounters& counters) {
  if (scene.hides_emitters() && !st.scattered) return finish_path(Rgb(0.0f), Rgb(0.0f), counters);
  return finish_path(st.result, st.direct, counters);
}

// ---- The ray casts, counted (and logged for gdvr-bench) as they are made ----

inline void log_ray(const Ray& ray, bool shadow, GeometrySet set, uint32_t stream, PathCounters& counters,
                    RayCoherence coherence = RayCoherence::kIncoherent) {
  ++counters.rays;
  if (counters.ray_log)
    counters.ray_log->push_back({ray, shadow, set, coherence == RayCoherence::kCoherent, stream});
}

// The last ray under max_depth looks for emission only, so it does not ask
// for the closest hit in the whole scene. It asks the emitters-only BVH
// (GeometrySet::kEmitters: a few spheres or quads in most scenes) which
// emitter it would reach, then, with an any-hit query that stops at the first
// blocker, whether anything lies before it; a ray that reaches no emitter in a
// scene without an environment needs no second query. The answer is the
// closest-hit query's: an emitter is seen iff nothing lies before it, and
// whatever lies before it emits nothing (it would be the closest emitter).
// The second query stops short of the emitter as a shadow ray does
// (kShadowEpsilon). On veach-mis (max_depth 3) this cut the render's
// instructions by 3.2 %.
//
// What the emitters-only query answered (`found`, `hit`) sets in st; returns
// whether the any-hit query over st->shadow must decide whether it is seen.
// The shadow ray is free: at a path's last ray no shadow ray is pending.
inline bool take_last_hit(const FrameScene& scene, bool found, const RayHit& hit, PathState* st) {
  st->hit = found;
  st->blocked = false;
  if (found) {
    scene.interaction(st->ray, hit, &st->si);
    st->shadow = st->ray;
    // si.t, not hit.t: a sphere's t is solved from the ray alone, so single
    // and stream casts ask the same any-hit question.
    st->shadow.tmax = st->si.t * (1.0f - kShadowEpsilon);
    return true;
  }
  st->shadow = st->ray;
  return scene.has_environment();
}

inline void cast_last(const FrameScene& scene, PathState* st, PathCounters& counters) {
  log_ray(st->ray, false, GeometrySet::kEmitters, 0, counters);
  RayHit hit;
  const bool found = scene.intersect_emitter_hit(st->ray, &hit);
  if (!take_last_hit(scene, found, hit, st)) return;
  log_ray(st->shadow, true, GeometrySet::kAll, 0, counters);
  st->blocked = scene.occluded(st->shadow);
}

// What the closest-hit query of a path's ray at `depth` tests: camera rays
// pass through the emitters of a scene that hides them
// (FrameScene::camera_geometry).
inline GeometrySet closest_hit_geometry(const FrameScene& scene, int depth) {
  return depth == 0 ? scene.camera_geometry() : GeometrySet::kAll;
}

inline void cast_closest(const FrameScene& scene, const PathTracerSettings& settings, PathState* st,
                         PathCounters& counters) {
  if (st->depth >= last_vertex_depth(settings)) {
    cast_last(scene, st, counters);
    return;
  }
  const GeometrySet set = closest_hit_geometry(scene, st->depth);
  log_ray(st->ray, false, set, 0, counters);
  RayHit hit;
  st->hit = scene.intersect_hit(st->ray, &hit, set);
  if (st->hit) scene.interaction(st->ray, hit, &st->si);
}

inline bool cast_shadow(const FrameScene& scene, const PathState& st, PathCounters& counters) {
  log_ray(st.shadow, true, GeometrySet::kAll, 0, counters);
  return scene.occluded(st.shadow);
}

// The same casts for the paths paths[which[0..n)] (n <= kPathBatch) at once, as one stream
// query (Accelerator::intersect_stream). The answers are those of the single
// casts: triangle hits bit for bit (but at exact ties in coherent streams),
// and a sphere's hit point is solved from the ray in
// FrameScene::interaction, not taken from the kernel's rounding.
// `shadow`: the paths' shadow rays, else their next rays.
inline void log_stream(const PathState* paths, const int* which, int n, bool shadow, GeometrySet set,
                       RayCoherence coherence, PathCounters& counters) {
  if (!counters.ray_log) {
    counters.rays += uint64_t(n);
    return;
  }
  const uint32_t stream = ++counters.streams_logged;
  for (int k = 0; k < n; ++k) {
    const PathState& st = paths[which[k]];
    log_ray(shadow ? st.shadow : st.ray, shadow, set, stream, counters, coherence);
  }
}

// Room for one stream query's rays and answers, in Embree's own records
// (RayStreamBuffer): the paths' rays go in, and the hits are read out, without
// a staging copy. Made once per batch, not per cast.
using RayStream = RayStreamBuffer;
static_assert(RayStream::kCapacity >= kPathBatch);

// cast_last() for each of paths[which[0..n)]: two streams, the first of them
// `coherence`.
inline void cast_last_stream(const FrameScene& scene, PathState* paths, const int* which, int n,
                             RayCoherence coherence, RayStream& stream, PathCounters& counters) {
  log_stream(paths, which, n, false, GeometrySet::kEmitters, coherence, counters);
  for (int k = 0; k < n; ++k) set_stream_ray(stream, k, paths[which[k]].ray);
  scene.accelerator().intersect_stream(stream, n, GeometrySet::kEmitters, coherence);
  int undecided[kPathBatch];
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const bool found = stream.found(k);
    if (take_last_hit(scene, found, found ? stream.hit(k) : RayHit{}, &paths[which[k]])) undecided[m++] = which[k];
  }
  if (m == 0) return;
  log_stream(paths, undecided, m, true, GeometrySet::kAll, RayCoherence::kIncoherent, counters);
  for (int k = 0; k < m; ++k) set_stream_ray(stream, k, paths[undecided[k]].shadow);
  scene.accelerator().occluded_stream(stream, m);
  for (int k = 0; k < m; ++k) paths[undecided[k]].blocked = stream.occluded(k);
}

// The closest hits of paths[which[0..n)] (none at its last ray) as one stream.
inline void cast_inner_stream(const FrameScene& scene, PathState* paths, const int* which, int n,
                              RayCoherence coherence, RayStream& stream, PathCounters& counters) {
  const GeometrySet set = closest_hit_geometry(scene, paths[which[0]].depth);
  log_stream(paths, which, n, false, set, coherence, counters);
  for (int k = 0; k < n; ++k) set_stream_ray(stream, k, paths[which[k]].ray);
  scene.accelerator().intersect_stream(stream, n, set, coherence);
  for (int k = 0; k < n; ++k) {
    PathState& st = paths[which[k]];
    st.hit = stream.found(k);
    if (st.hit) scene.interaction(st.ray, stream.hit(k), &st.si);
  }
}

// cast_closest() for each of paths[which[0..n)]. A batch's paths take their
// vertices in step (path_batch.cpp: all start at depth 0, and every path
// that goes on goes one deeper), so its rays are all last rays or none and
// the first path decides for the stream (sorting each stream's paths by
// depth cost 0.6 % of cbox's instructions). PathBatchTest checks the batches
// against trace_path, which decides path by path.
//
// The same holds for coherence: at depth 0 the stream is the batch's camera
// rays, which trace_tile_samples fills with consecutive samples of
// neighbouring pixels, so Embree traces them as coherent packets (5-10 % less
// render time; every later stream has parted). Their hits are those of single
// casts but at exact ties (RayCoherence in accelerator.h).
inline void cast_closest_stream(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths,
                                const int* which, int n, RayStream& stream, PathCounters& counters) {
  if (n <= 0) return;
  const PathState& first = paths[which[0]];
  const RayCoherence coherence = first.depth == 0 ? RayCoherence::kCoherent : RayCoherence::kIncoherent;
  if (first.depth >= last_vertex_depth(settings)) cast_last_stream(scene, paths, which, n, coherence, stream, counters);
  else cast_inner_stream(scene, paths, which, n, coherence, stream, counters);
}

// resolve_shadow() for each of paths[which[0..n)].
inline void cast_shadow_stream_and_resolve(const FrameScene& scene, PathState* paths, const int* which, int n,
                                           RayStream& stream, PathCounters& counters) {
  log_stream(paths, which, n, true, GeometrySet::kAll, RayCoherence::kIncoherent, counters);
  for (int k = 0; k < n; ++k) set_stream_ray(stream, k, paths[which[k]].shadow);
  scene.accelerator().occluded_stream(stream, n);
  for (int k = 0; k < n; ++k) resolve_shadow(stream.occluded(k), &paths[which[k]]);
}

}  // namespace gdvr
