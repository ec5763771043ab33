// The path tracer's work per vertex, cut at its two ray casts so that a path
// can wait between them. trace_path() runs one path through these stages;
// trace_path_batch() (path_batch.h) runs a batch of paths stage by stage, so
// that many independent paths' shading sits between two ray casts. Both call
// the same functions, so a path's radiance is the same bit for bit whichever
// driver ran it.
//
// Per vertex:
//   [closest hit] -> add_emission -> sample_emitter -> connect_emitter
//                 -> sample_bsdf -> [shadow ray] -> resolve_shadow
// The emitter's contribution waits in the state until its shadow ray is
// answered. The stages draw the path's numbers in the order
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
// the stream casts below take at once. The states (~300 bytes each) stay in
// L1/L2.
constexpr int kPathBatch = 64;

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
  SurfaceInteraction si;  // the vertex it found
  const Bsdf* bsdf = nullptr;  // its BSDF
  bool continues = true;  // false once the path has no next ray

  EmitterSample emitter;  // next-event estimation's sample at si

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
  st->shadow_pending = false;
}

// Before `ray` is cast: the emitter sample at the vertex it finds draws the
// next three numbers; an environment map's tables miss the cache, so their
// loads start now and overlap the traversal (frame_scene.h).
inline void prefetch_for_next_vertex(const FrameScene& scene, const PathState& st) {
  scene.prefetch_next_emitter_sample(st.sampler);
}

// The depth of a path's last vertex under max_depth (INT_MAX: unbounded).
// There only emission seen along the ray counts; nothing is sampled. A stream
// query computes it once for all its hits.
inline int last_vertex_depth(const PathTracerSettings& settings) {
  return settings.max_depth >= 0 ? settings.max_depth - 1 : std::numeric_limits<int>::max();
}

// Fills st->si for the closest hit `hit` of st->ray. At the last vertex a hit
// on a shape that emits nothing contributes nothing, and add_emission reads
// only its shape there, so the shading data (interpolation, frame, uv) is not
// computed (on veach-mis, max_depth 3, up to a third of the closest hits).
inline void take_hit(const FrameScene& scene, int last_depth, const RayHit& hit, PathState* st) {
  if (st->depth >= last_depth && scene.emitter_of_shape(hit.id) < 0) {
    st->si.shape = hit.id;
    return;
  }
  scene.interaction(st->ray, hit, &st->si);
}

// ---- After the closest-hit query (st->hit, st->si) ----

// Emission seen along the ray, weighted against emitter sampling. Sets
// st->continues: whether the path goes on from this vertex.
inline void add_emission(const FrameScene& scene, const PathTracerSettings& settings, PathState* st) {
  const SurfaceInteraction& si = st->si;
  if (!(st->depth == 0 && settings.hide_emitters)) {
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

// BSDF sampling, the next ray and Russian roulette. Sets st->continues.
inline void sample_bsdf(const PathTracerSettings& settings, PathState* st) {
  const SurfaceInteraction& si = st->si;
  st->continues = false;
  float u_lobe = st->sampler.next_1d();
  Vec2f u_dir = st->sampler.next_2d();
  BsdfSample bs;
  // bsdf_sample() returns only finite weights, pdfs and directions.
  if (!bsdf_sample(*st->bsdf, si.uv, si.wi, u_lobe, u_dir, &bs) || bs.weight.is_black()) return;
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

// The answer to st->shadow.
inline void resolve_shadow(bool occluded, PathState* st) {
  if (!occluded) st->result += st->shadow_contribution;
  st->shadow_pending = false;
}

inline PathSample finish_path(const PathState& st, PathCounters& counters) {
  if (!is_finite(st.result)) {
    ++counters.invalid_samples;
    return PathSample{};
  }
  PathSample out;
  out.radiance = st.result;
  out.direct = st.direct;
  return out;
}

// The two ray casts, counted (and logged for gdvr-bench) as they are made.
inline void cast_closest(const FrameScene& scene, const PathTracerSettings& settings, PathState* st,
                         PathCounters& counters) {
  ++counters.rays;
  if (counters.ray_log) counters.ray_log->push_back({st->ray, false});
  RayHit hit;
  st->hit = scene.intersect_hit(st->ray, &hit);
  if (st->hit) take_hit(scene, last_vertex_depth(settings), hit, st);
}

inline bool cast_shadow(const FrameScene& scene, const PathState& st, PathCounters& counters) {
  ++counters.rays;
  if (counters.ray_log) counters.ray_log->push_back({st.shadow, true});
  return scene.occluded(st.shadow);
}

// The same casts for the paths paths[which[0..n)] (n <= kPathBatch) at once, as one stream
// query (Accelerator::intersect_stream). The answers are those of the single
// casts: triangle hits bit for bit, and a sphere's hit point is solved from
// the ray in FrameScene::interaction, not taken from the kernel's rounding.
inline void log_stream(const PathState* paths, const int* which, int n, bool shadow, PathCounters& counters) {
  counters.rays += uint64_t(n);
  if (!counters.ray_log) return;
  const uint32_t stream = ++counters.streams_logged;
  for (int k = 0; k < n; ++k) {
    const PathState& st = paths[which[k]];
    counters.ray_log->push_back({shadow ? st.shadow : st.ray, shadow, stream});
  }
}

// Room for one stream query's rays and answers, in Embree's own records
// (RayStreamBuffer): the paths' rays go in, and the hits are read out, without
// a staging copy. Made once per batch, not per cast.
using RayStream = RayStreamBuffer;
static_assert(RayStream::kCapacity >= kPathBatch);

inline void cast_closest_stream(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths,
                                const int* which, int n, RayStream& stream, PathCounters& counters) {
  log_stream(paths, which, n, false, counters);
  for (int k = 0; k < n; ++k) set_stream_ray(stream, k, paths[which[k]].ray);
  scene.accelerator().intersect_stream(stream, n);
  const int last_depth = last_vertex_depth(settings);
  for (int k = 0; k < n; ++k) {
    PathState& st = paths[which[k]];
    st.hit = stream.found(k);
    if (st.hit) take_hit(scene, last_depth, stream.hit(k), &st);
  }
}

// resolve_shadow() for each of paths[which[0..n)].
inline void cast_shadow_stream_and_resolve(const FrameScene& scene, PathState* paths, const int* which, int n,
                                           RayStream& stream, PathCounters& counters) {
  log_stream(paths, which, n, true, counters);
  for (int k = 0; k < n; ++k) set_stream_ray(stream, k, paths[which[k]].shadow);
  scene.accelerator().occluded_stream(stream, n);
  for (int k = 0; k < n; ++k) resolve_shadow(stream.occluded(k), &paths[which[k]]);
}

}  // namespace gdvr
