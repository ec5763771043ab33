#include "core/render/vector_batch.h"

#include "core/render/path_batch.h"

#include <utility>

namespace gdvr {
namespace {

static_assert(kVectorBatch == kPathBatch, "the vector batch takes the path batch's paths");

Vec3f lane3(const float (*a)[kVectorBatch], int i) { return {a[0][i], a[1][i], a[2][i]}; }
Rgb lane_rgb(const float (*a)[kVectorBatch], int i) { return {a[0][i], a[1][i], a[2][i]}; }
void set_lane(float (*a)[kVectorBatch], int i, Vec3f v) { a[0][i] = v.x, a[1][i] = v.y, a[2][i] = v.z; }
void set_lane(float (*a)[kVectorBatch], int i, Rgb c) { a[0][i] = c.r, a[1][i] = c.g, a[2][i] = c.b; }

Ray ray_of(const VectorBatchState& s, int i) { return {lane3(s.o, i), lane3(s.d, i), s.tmin[i], s.tmax[i]}; }
Ray shadow_ray_of(const VectorBatchState& s, int i) {
  return {lane3(s.shadow_o, i), lane3(s.shadow_d, i), 0.0f, s.shadow_tmax[i]};
}

// A path's state between vertices into lane i, field by field (store_path's inverse).
void load_path(const PathState& st, int i, VectorBatchState* s) {
  s->rng_state[i] = st.sampler.generator().state();
  s->rng_inc[i] = st.sampler.generator().increment();
  set_lane(s->o, i, st.ray.o);
  set_lane(s->d, i, st.ray.d);
  s->tmin[i] = st.ray.tmin;
  s->tmax[i] = st.ray.tmax;
  set_lane(s->throughput, i, st.throughput);
  set_lane(s->result, i, st.result);
  set_lane(s->direct, i, st.direct);
  set_lane(s->prev_p, i, st.prev_p);
  s->prev_pdf[i] = st.prev_bsdf_pdf;
  s->eta[i] = st.eta;
  s->prev_delta[i] = st.prev_bsdf_delta ? -1 : 0;
  s->depth[i] = st.depth;
}

// Lane i's whole state back into its PathState, for the scalar stages.
void store_path(const VectorBatchState& s, int i, PathState* st) {
  st->sampler.generator().restore(s.rng_state[i], s.rng_inc[i]);
  st->ray = ray_of(s, i);
  st->throughput = lane_rgb(s.throughput, i);
  st->result = lane_rgb(s.result, i);
  st->direct = lane_rgb(s.direct, i);
  st->prev_p = lane3(s.prev_p, i);
  st->prev_bsdf_pdf = s.prev_pdf[i];
  st->eta = s.eta[i];
  st->prev_bsdf_delta = s.prev_delta[i] != 0;
  st->depth = s.depth[i];
  st->shadow_pending = false;
}

// log_stream() for lanes which[0..n), whose rays are ray_of_lane(i).
template <class RayOfLane>
void log_lanes(const int* which, int n, bool shadow, GeometrySet set, RayCoherence coherence,
               PathCounters& counters, RayOfLane ray_of_lane) {
  if (!counters.ray_log) {
    counters.rays += uint64_t(n);
    return;
  }
  const uint32_t stream = ++counters.streams_logged;
  for (int k = 0; k < n; ++k) log_ray(ray_of_lane(which[k]), shadow, set, stream, counters, coherence);
}

// add_emission() for lane i, whose ray hit an emitter (`hit`) or left the
// scene (null: the environment's radiance): through a PathState, so that the
// sums come out as the scalar stage leaves them. Scalar: a few per cent of
// hits, and it needs the emitter's own pdf.
void add_emission_on_lane(const FrameScene& scene, const PathTracerSettings& settings, VectorBatchState* s, int i,
                          const RayHit* hit, PathState* scratch) {
  scratch->ray = ray_of(*s, i);
  scratch->hit = hit != nullptr;
  scratch->blocked = false;
  if (hit) scene.interaction(scratch->ray, *hit, &scratch->si);
  scratch->depth = s->depth[i];
  scratch->throughput = lane_rgb(s->throughput, i);
  scratch->result = lane_rgb(s->result, i);
  scratch->direct = lane_rgb(s->direct, i);
  scratch->prev_p = lane3(s->prev_p, i);
  scratch->prev_bsdf_pdf = s->prev_pdf[i];
  scratch->prev_bsdf_delta = s->prev_delta[i] != 0;
  add_emission(scene, settings, scratch);
  set_lane(s->result, i, scratch->result);
  set_lane(s->direct, i, scratch->direct);
}

// The whole vertex of lane i, whose hit the kernel does not shade (a sphere,
// a BSDF it lacks: kShapeScalar), by the scalar stages through a PathState,
// in path_batch.cpp's order: emission, the emitter sample and its BSDF
// value, the BSDF sample and Russian roulette.
void shade_vertex_on_lane(const FrameScene& scene, const PathTracerSettings& settings, VectorBatchState* s, int i,
                          const RayHit& hit, PathState* st) {
  store_path(*s, i, st);
  st->hit = true;
  st->blocked = false;
  scene.interaction(st->ray, hit, &st->si);
  add_emission(scene, settings, st);
  if (st->continues) {
    sample_emitter(scene, st);
    connect_emitter(st);
    sample_bsdf(settings, st);
  }
  // The whole state back (a path that ended keeps only its sums' meaning).
  load_path(*st, i, s);
  s->continues[i] = st->continues ? -1 : 0;
  s->shadow_pending[i] = st->shadow_pending ? -1 : 0;
  if (st->shadow_pending) {
    set_lane(s->shadow_o, i, st->shadow.o);
    set_lane(s->shadow_d, i, st->shadow.d);
    s->shadow_tmax[i] = st->shadow.tmax;
    set_lane(s->shadow_contribution, i, st->shadow_contribution);
  }
}

// add_emission() for lanes[0..n), whose rays left the scene: by the kernel
// where the environment is a map, else lane by lane.
void add_environment(const FrameScene& scene, const PathTracerSettings& settings, const VectorSceneView& view,
                     const VectorKernel& kernel, VectorBatchState* s, const int32_t* lanes, int n,
                     PathState* scratch) {
  if (n == 0 || !scene.has_environment()) return;
  if (view.envmap) {
    kernel.add_environment(view, s, lanes, n, settings.hide_emitters);
    return;
  }
  for (int k = 0; k < n; ++k) add_emission_on_lane(scene, settings, s, lanes[k], nullptr, scratch);
}

// cast_last_stream() and add_emission() for lanes live[0..count), whose rays
// are their paths' last under max_depth: the emitters-only query, the any-hit
// query before the emitter (or, for a ray that found none, towards the
// environment) and the emission of those that see it.
void cast_last_rays(const FrameScene& scene, const PathTracerSettings& settings, const VectorSceneView& view,
                    const VectorKernel& kernel, VectorBatchState* s, const int* live, int count,
                    RayCoherence coherence, RayStream& stream, PathCounters& counters, PathState* scratch) {
  log_lanes(live, count, false, GeometrySet::kEmitters, coherence, counters, [s](int i) { return ray_of(*s, i); });
  for (int k = 0; k < count; ++k) {
    const int i = live[k];
    stream.set(k, lane3(s->o, i), lane3(s->d, i), s->tmin[i], s->tmax[i]);
  }
  scene.accelerator().intersect_stream(stream, count, GeometrySet::kEmitters, coherence);
  // take_last_hit: the any-hit query is the ray itself (tmin included),
  // stopped short of the emitter at the interaction's distance; a ray that
  // found no emitter asks it whole where an environment would be seen.
  int found[kPathBatch];
  RayHit hits[kPathBatch];
  bool escaped[kPathBatch];
  int m = 0;
  for (int k = 0; k < count; ++k) {
    const int i = live[k];
    escaped[m] = !stream.found(k);
    if (escaped[m]) {
      if (!scene.has_environment()) continue;
      s->shadow_tmax[i] = s->tmax[i];
    } else {
      hits[m] = stream.hit(k);
      scene.interaction(ray_of(*s, i), hits[m], &scratch->si);
      s->shadow_tmax[i] = scratch->si.t * (1.0f - kShadowEpsilon);
    }
    found[m++] = i;
  }
  if (m == 0) return;
  const auto before_emitter = [s](int i) {
    Ray r = ray_of(*s, i);
    r.tmax = s->shadow_tmax[i];
    return r;
  };
  log_lanes(found, m, true, GeometrySet::kAll, RayCoherence::kIncoherent, counters, before_emitter);
  for (int k = 0; k < m; ++k) {
    const Ray r = before_emitter(found[k]);
    stream.set(k, r.o, r.d, r.tmin, r.tmax);
  }
  scene.accelerator().occluded_stream(stream, m);
  int32_t seen_environment[kPathBatch];
  int e = 0;
  for (int k = 0; k < m; ++k) {
    if (stream.occluded(k)) continue;
    if (escaped[k]) seen_environment[e++] = found[k];
    else add_emission_on_lane(scene, settings, s, found[k], &hits[k], scratch);
  }
  add_environment(scene, settings, view, kernel, s, seen_environment, e, scratch);
}

// Exchanges every per-lane field of lanes a and b.
void swap_lanes(VectorBatchState& s, int a, int b) {
  auto sw = [a, b](auto* field) { std::swap(field[a], field[b]); };
  sw(s.rng_state), sw(s.rng_inc);
  for (int c = 0; c < 3; ++c) {
    sw(s.o[c]), sw(s.d[c]), sw(s.throughput[c]), sw(s.result[c]), sw(s.direct[c]), sw(s.prev_p[c]);
    sw(s.shadow_o[c]), sw(s.shadow_d[c]), sw(s.shadow_contribution[c]);
  }
  sw(s.tmin), sw(s.tmax), sw(s.prev_pdf), sw(s.eta), sw(s.prev_delta), sw(s.depth);
  sw(s.hit_shape), sw(s.hit_prim), sw(s.hit_u), sw(s.hit_v), sw(s.shade), sw(s.continues);
  sw(s.shadow_tmax), sw(s.shadow_pending);
}

// Lane `from`, which the kernel shades next, into lane `to`, whose path has
// ended (now or before): what the kernel reads of a lane (its inputs in
// vector_batch_state.h) goes to `to`, and the two lanes trade their sums,
// which are all that is left of an ended path. Cheaper than swap_lanes by
// half the fields, which mattered (1.010x on matpreview, 24 pairs).
void move_shaded_lane(VectorBatchState& s, int from, int to) {
  s.rng_state[to] = s.rng_state[from], s.rng_inc[to] = s.rng_inc[from];
  for (int c = 0; c < 3; ++c) {
    s.d[c][to] = s.d[c][from];
    s.throughput[c][to] = s.throughput[c][from];
    std::swap(s.result[c][to], s.result[c][from]);
    std::swap(s.direct[c][to], s.direct[c][from]);
  }
  s.eta[to] = s.eta[from], s.depth[to] = s.depth[from];
  s.hit_shape[to] = s.hit_shape[from], s.hit_prim[to] = s.hit_prim[from];
  s.hit_u[to] = s.hit_u[from], s.hit_v[to] = s.hit_v[from];
  s.shade[to] = s.shade[from];
  s.shade[from] = 0;
}

// Moves the lanes marked in s.shade to the front of lanes [0, n), so that
// the kernel's groups of eight are full: it costs a group of eight whatever
// number of lanes it shades, and where paths have ended or left the scene
// a group had 4.2 of 8 on matpreview. Each path keeps its numbers; what
// moves with it is tracked in origin (lane -> the batch's path index) and
// live[0..count) (the lanes traced this round, whose order, the streams'
// order, stays as it was). A lane the scalar stages shaded this round
// (scalar_shaded) is whole and live, so it trades all its fields.
void pack_shaded_lanes(VectorBatchState& s, int n, int32_t* scalar_shaded, int* origin, int* live, int count) {
  int slot_of[kPathBatch];  // lane -> its place in live, or -1
  for (int i = 0; i < n; ++i) slot_of[i] = -1;
  for (int k = 0; k < count; ++k) slot_of[live[k]] = k;
  int lo = 0, hi = n - 1;
  while (true) {
    while (lo < hi && s.shade[lo]) ++lo;
    while (lo < hi && !s.shade[hi]) --hi;
    if (lo >= hi) return;
    if (scalar_shaded[lo]) swap_lanes(s, lo, hi);
    else move_shaded_lane(s, hi, lo);
    std::swap(origin[lo], origin[hi]);
    std::swap(scalar_shaded[lo], scalar_shaded[hi]);
    if (slot_of[lo] >= 0) live[slot_of[lo]] = hi;
    if (slot_of[hi] >= 0) live[slot_of[hi]] = lo;
    std::swap(slot_of[lo], slot_of[hi]);
    ++lo, --hi;
  }
}

}  // namespace

const std::vector<VectorKernel>& vector_kernels() {
  static const std::vector<VectorKernel> kernels = [] {
    std::vector<VectorKernel> k;
#if defined(GDVR_AVX2_KERNELS)
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
        __builtin_cpu_supports("avx512dq"))
      k.push_back({"avx512", shade_vector_vertices_avx512, add_environment_avx512});
    if (__builtin_cpu_supports("avx2")) k.push_back({"avx2", shade_vector_vertices_avx2, add_environment_avx2});
#endif
    return k;
  }();
  return kernels;
}

bool vector_batch_available(const FrameScene& scene) {
  return !vector_kernels().empty() && scene.vector_scene() != nullptr;
}

std::string why_no_vector_batch(const FrameScene& scene, const PathTracerSettings& settings, int paths_in_flight) {
  if (!settings.vector_kernels) return "vector kernels are switched off";
  if (paths_in_flight < kPathBatch) return "paths are traced " + std::to_string(paths_in_flight) + " at a time";
  if (!scene.vector_scene()) return scene.why_not_vector();
  if (vector_kernels().empty()) return "this CPU has no AVX2";
  return "";
}

void start_lane(VectorBatchState* s, int i, const Ray& camera_ray, const Sampler& sampler) {
  s->rng_state[i] = sampler.generator().state();
  s->rng_inc[i] = sampler.generator().increment();
  set_lane(s->o, i, camera_ray.o);
  set_lane(s->d, i, camera_ray.d);
  s->tmin[i] = camera_ray.tmin;
  s->tmax[i] = camera_ray.tmax;
  set_lane(s->throughput, i, Rgb(1.0f));
  set_lane(s->result, i, Rgb(0.0f));
  set_lane(s->direct, i, Rgb(0.0f));
  set_lane(s->prev_p, i, camera_ray.o);
  s->prev_pdf[i] = 1.0f;
  s->eta[i] = 1.0f;
  s->prev_delta[i] = -1;
  s->depth[i] = 0;
}

void trace_vector_batch(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths, int n,
                        RayStream& stream, PathCounters& counters, PathSample* out, const VectorKernel* kernel) {
  if (!scene.vector_scene() || (!kernel && vector_kernels().empty())) {
    // Callers check vector_batch_available(); this keeps a careless one correct.
    trace_path_batch(scene, settings, paths, n, counters, out);
    return;
  }
  VectorBatchState s;
  for (int i = 0; i < n; ++i) load_path(paths[i], i, &s);
  trace_started_vector_batch(scene, settings, &s, n, stream, counters, out, kernel);
}

void trace_started_vector_batch(const FrameScene& scene, const PathTracerSettings& settings, VectorBatchState* state,
                                int n, RayStream& stream, PathCounters& counters, PathSample* out,
                                const VectorKernel* kernel) {
  if (!kernel) kernel = &vector_kernels().front();
  VectorSceneView view = scene.vector_scene()->view();
  view.rr_depth = settings.rr_depth;
  VectorBatchState& s = *state;
  for (int i = 0; i < kVectorBatch; ++i) s.shade[i] = s.continues[i] = s.shadow_pending[i] = 0;
  int live[kPathBatch], shadowed[kPathBatch];
  int32_t scalar_shaded[kPathBatch] = {};  // -1 where shade_vertex_on_lane shaded the vertex
  int count = n;
  for (int i = 0; i < n; ++i) live[i] = i;
  int origin[kPathBatch];  // lane -> the index of the path it holds (pack_shaded_lanes moves paths)
  for (int i = 0; i < n; ++i) origin[i] = i;
  PathState scratch;
  // The batch's paths take their vertices in step (path_batch.cpp), so the
  // live ones share one depth.
  const int last = last_vertex_depth(settings);
  for (int depth = 0; count > 0 && depth < last; ++depth) {
    // ---- Closest hits: one stream, as cast_inner_stream ----
    const RayCoherence coherence = depth == 0 ? RayCoherence::kCoherent : RayCoherence::kIncoherent;
    const GeometrySet set = closest_hit_geometry(scene, depth);
    log_lanes(live, count, false, set, coherence, counters, [&](int i) { return ray_of(s, i); });
    for (int k = 0; k < count; ++k) {
      const int i = live[k];
      stream.set(k, lane3(s.o, i), lane3(s.d, i), s.tmin[i], s.tmax[i]);
    }
    scene.accelerator().intersect_stream(stream, count, set, coherence);
    int32_t escaped[kPathBatch];
    int escapes = 0;
    for (int k = 0; k < count; ++k) {
      const int i = live[k];
      if (!stream.found(k)) {  // the path ends, seeing the environment if there is one
        escaped[escapes++] = i;
        continue;
      }
      const RayHit hit = stream.hit(k);
      const uint32_t flags = view.shape_flags[hit.id];
      if (flags & kShapeReflectsNothing) {
        // add_emission, then the path ends (kShapeReflectsNothing).
        if (scene.emitter_of_shape(hit.id) >= 0 && !(depth == 0 && settings.hide_emitters))
          add_emission_on_lane(scene, settings, &s, i, &hit, &scratch);
        s.continues[i] = s.shadow_pending[i] = 0;
        scalar_shaded[i] = -1;
        continue;
      }
      if (flags & kShapeScalar) {
        shade_vertex_on_lane(scene, settings, &s, i, hit, &scratch);
        scalar_shaded[i] = -1;
        continue;
      }
      // The kernel reads the triangle's records after the other hits and the
      // rays that left: asked for now, they arrive meanwhile (matpreview's
      // mesh does not fit the cache).
      const uint32_t record = view.shape_first[hit.id] + hit.prim;
      __builtin_prefetch(&view.triangles[record]);
      if (view.shading) __builtin_prefetch(&view.shading[record]);
      s.hit_shape[i] = hit.id;
      s.hit_prim[i] = int32_t(hit.prim);
      s.hit_u[i] = hit.u;
      s.hit_v[i] = hit.v;
      s.shade[i] = -1;
      if (scene.emitter_of_shape(hit.id) >= 0 && !(depth == 0 && settings.hide_emitters))
        add_emission_on_lane(scene, settings, &s, i, &hit, &scratch);
    }

    add_environment(scene, settings, view, *kernel, &s, escaped, escapes, &scratch);

    pack_shaded_lanes(s, n, scalar_shaded, origin, live, count);
    // ---- Eight paths' vertices at a time, in full groups ----
    kernel->shade(view, &s);

    // ---- Shadow rays as one stream, then the paths that go on (in order) ----
    // Without branches: which paths connect and go on is random, and
    // mispredicted branches here were a tenth of the driver's time.
    int pending = 0, next = 0;
    for (int k = 0; k < count; ++k) {
      const int i = live[k];
      const int32_t shaded = s.shade[i] | scalar_shaded[i];
      s.shade[i] = 0;
      scalar_shaded[i] = 0;
      shadowed[pending] = i;
      pending += (shaded & s.shadow_pending[i]) != 0;
      live[next] = i;
      next += (shaded & s.continues[i]) != 0;
    }
    if (pending > 0) {
      log_lanes(shadowed, pending, true, GeometrySet::kAll, RayCoherence::kIncoherent, counters,
                [&](int i) { return shadow_ray_of(s, i); });
      for (int k = 0; k < pending; ++k) {
        const int i = shadowed[k];
        stream.set(k, lane3(s.shadow_o, i), lane3(s.shadow_d, i), 0.0f, s.shadow_tmax[i]);
      }
      scene.accelerator().occluded_stream(stream, pending);
      for (int k = 0; k < pending; ++k) {
        const int i = shadowed[k];
        s.shadow_pending[i] = 0;
        if (!stream.occluded(k)) set_lane(s.result, i, lane_rgb(s.result, i) + lane_rgb(s.shadow_contribution, i));
      }
    }
    count = next;
  }

  // ---- The live paths' last ray, then every path's sums ----
  if (count > 0) {
    const RayCoherence coherence = last == 0 ? RayCoherence::kCoherent : RayCoherence::kIncoherent;
    cast_last_rays(scene, settings, view, *kernel, &s, live, count, coherence, stream, counters, &scratch);
  }
  for (int i = 0; i < n; ++i) out[origin[i]] = finish_path(lane_rgb(s.result, i), lane_rgb(s.direct, i), counters);
}

}  // namespace gdvr
