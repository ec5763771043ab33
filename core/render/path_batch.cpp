#include "core/render/path_batch.h"

#include <algorithm>
#include <memory>

#include "core/render/vector_batch.h"

namespace gdvr {
namespace {

// sample_bsdf for paths[which[0..n)], with the batch's Beckmann slope
// inversions (beckmann_slope.h) run side by side: each Newton step is one
// loop over all of them, so that the core overlaps their chains of dependent
// transcendental calls instead of waiting out one chain after the other
// (about half the time per inversion: docs/bsdf.md). Bit for bit what
// sample_bsdf gives each path.
inline void sample_bsdf_stage(const PathTracerSettings& settings, PathState* paths, const int* which, int n) {
  BeckmannSlopeInversion inversions[kPathBatch];
  int slot[kPathBatch];
  int m = 0;
  for (int k = 0; k < n; ++k) {
    PathState& st = paths[which[k]];
    draw_bsdf_numbers(&st);
    slot[k] = bsdf_start_slope_inversion(*st.bsdf, st.si.wi, st.u_lobe, st.u_dir, &inversions[m]) ? m++ : -1;
  }
  for (int step = 0; step < BeckmannSlopeInversion::kNewtonSteps; ++step)
    for (int i = 0; i < m; ++i) inversions[i].newton_step();
  Vec2f slopes[kPathBatch];
  for (int i = 0; i < m; ++i) slopes[i] = inversions[i].slope();
  for (int k = 0; k < n; ++k) sample_bsdf_drawn(settings, &paths[which[k]], slot[k] >= 0 ? &slopes[slot[k]] : nullptr);
}

// Advances paths[live[0..count)], whose rays are set, to their ends.
[[gnu::flatten]] void run_batch(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths,
                                int* live, int count, RayStream& stream, PathCounters& counters) {
  int shadowed[kPathBatch];
  cast_closest_stream(scene, settings, paths, live, count, stream, counters);
  while (count > 0) {
    // Each stage is its own loop: its body is short enough that the core runs
    // several paths' chains of square roots and divisions at once.
    int shading = 0;
    for (int k = 0; k < count; ++k) {
      PathState& st = paths[live[k]];
      add_emission(scene, settings, &st);
      if (st.continues) live[shading++] = live[k];
    }
    for (int k = 0; k < shading; ++k) sample_emitter(scene, &paths[live[k]]);
    for (int k = 0; k < shading; ++k) connect_emitter(&paths[live[k]]);
    sample_bsdf_stage(settings, paths, live, shading);
    // The batch's shadow rays as one stream, then its next rays as another
    // (Embree traces a stream faster per ray than single rays). Paths that
    // bounced stay in order, so the ray log is a pure function of the batch.
    int pending = 0;
    count = 0;
    for (int k = 0; k < shading; ++k) {
      PathState& st = paths[live[k]];
      if (st.shadow_pending) shadowed[pending++] = live[k];
      if (!st.continues) continue;
      prefetch_for_next_vertex(scene, st);
      live[count++] = live[k];
    }
    if (pending > 0) cast_shadow_stream_and_resolve(scene, paths, shadowed, pending, stream, counters);
    if (count > 0) cast_closest_stream(scene, settings, paths, live, count, stream, counters);
  }
}

void trace_at_most_one_batch(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths, int n,
                             RayStream& stream, PathCounters& counters, PathSample* out) {
  int live[kPathBatch];
  for (int i = 0; i < n; ++i) {
    prefetch_for_next_vertex(scene, paths[i]);
    live[i] = i;
  }
  run_batch(scene, settings, paths, live, n, stream, counters);
  for (int i = 0; i < n; ++i) out[i] = finish_path(scene, paths[i], counters);
}

}  // namespace

void trace_path_batch(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths, int n,
                      PathCounters& counters, PathSample* out) {
  RayStream stream;
  for (int base = 0; base < n; base += kPathBatch)
    trace_at_most_one_batch(scene, settings, paths + base, std::min(kPathBatch, n - base), stream, counters,
                            out + base);
}

void trace_tile_samples(const FrameScene& scene, const PathTracerSettings& settings, const PerspectiveCamera& camera,
                        uint64_t seed, uint32_t frame, const Tile& tile, int first_sample, int count,
                        int paths_in_flight, PathCounters& counters, const std::function<void(int x, int y, const PathSample&)>& add) {
  const int batch = std::clamp(paths_in_flight, 1, kPathBatch);
  // A full batch of a scene with records goes to the vector batch, its paths
  // started in place; one path at a time (a benchmark's baseline) stays scalar.
  const bool vector = settings.vector_kernels && batch == kPathBatch && vector_batch_available(scene);
  std::unique_ptr<VectorBatchState> lanes(vector ? new VectorBatchState : nullptr);
  std::unique_ptr<PathState[]> paths(vector ? nullptr : new PathState[kPathBatch]);
  PathSample out[kPathBatch];
  RayStream stream;
  int px[kPathBatch], py[kPathBatch];
  int n = 0;
  auto flush = [&] {
    if (vector) trace_started_vector_batch(scene, settings, lanes.get(), n, stream, counters, out);
    else trace_at_most_one_batch(scene, settings, paths.get(), n, stream, counters, out);
    for (int i = 0; i < n; ++i) add(px[i], py[i], out[i]);
    n = 0;
  };
  for (int y = tile.y0; y < tile.y1; ++y)
    for (int x = tile.x0; x < tile.x1; ++x) {
      const Sampler::PixelKey pixel(seed, frame, uint32_t(x), uint32_t(y));
      for (int s = first_sample; s < first_sample + count; ++s) {
        Sampler sampler(pixel, uint32_t(s));
        Vec2f jitter = sampler.next_2d();  // box filter: uniform within the pixel
        const Ray ray = camera.generate_ray({float(x) + jitter.x, float(y) + jitter.y});
        if (vector) start_lane(lanes.get(), n, ray, sampler);
        else start_path(&paths[n], ray, sampler);
        px[n] = x;
        py[n] = y;
        if (++n == batch) flush();
      }
    }
  if (n > 0) flush();
}

}  // namespace gdvr
