// Unidirectional path tracing with next-event estimation and BSDF sampling
// combined by the power heuristic (Veach 1997, Sec. 9.2), written to match Mitsuba
// 3's `path` integrator: max_depth counts path segments (1 = emitters seen
// directly, -1 = unbounded), Russian roulette from rr_depth with survival
// min(max(throughput) * eta^2, 1) (russian_roulette.h: Mitsuba caps it at 0.95).
#pragma once

#include <cstdint>
#include <vector>

#include "core/math/rng.h"
#include "core/render/frame_scene.h"

namespace gdvr {

// "Unbounded" (max_depth -1) still ends here. Survival min(throughput * eta^2,
// 1) never ends a path that loses no energy: light caught by total internal
// reflection in a glass cube, a mirror box, a furnace of albedo 1. Mitsuba's
// 0.95 cap would end them but makes deep paths' variance grow without bound
// (russian_roulette.h), so gdvr caps the depth instead. A scene losing even
// 0.01 % per bounce keeps 0.0014 of its light past this depth; each sample
// costs at most this many bounces, so a render (and its cancellation, checked
// per tile) always finishes.
constexpr int kUnboundedDepthLimit = 65536;

struct PathTracerSettings {
  int max_depth = -1;  // -1: unbounded, up to kUnboundedDepthLimit
  int rr_depth = 5;
  bool hide_emitters = false;
  // The vector batch's AVX2/AVX-512 kernel where the scene and the CPU allow it
  // (vector_batch.h). Off: the scalar batch, which gives the same image bit
  // for bit (tests and benchmarks compare the two).
  bool vector_kernels = true;
};

// A ray as traced, for benchmarks that replay the path tracer's exact ray
// distribution through bare ray casting (gdvr-bench).
struct RecordedRay {
  Ray ray;
  bool shadow = false;  // any-hit query
  GeometrySet set = GeometrySet::kAll;  // what a closest-hit query tests
  bool coherent = false;  // cast in a stream flagged RayCoherence::kCoherent
  // Rays cast together in one stream query share a stream number (from 1);
  // 0 for a ray cast on its own.
  uint32_t stream = 0;
};

// The number of path segments a path may have: max_depth, or
// kUnboundedDepthLimit for -1.
inline int path_depth_limit(const PathTracerSettings& settings) {
  return settings.max_depth >= 0 ? settings.max_depth : kUnboundedDepthLimit;
}

struct PathCounters {
  uint64_t rays = 0;            // closest-hit (all or emitters-only) and shadow rays
  uint64_t invalid_samples = 0; // non-finite radiance dropped (reported, never silent)
  std::vector<RecordedRay>* ray_log = nullptr;  // benchmarks only; null in renders
  uint32_t streams_logged = 0;                  // the last RecordedRay::stream handed out
};

struct PathSample {
  Rgb radiance;  // everything, including `direct`
  Rgb direct;    // emitters seen directly from the camera (kept out of gradient solves)
};

PathSample trace_path(const FrameScene& scene, const PathTracerSettings& settings, const Ray& camera_ray,
                      Sampler& sampler, PathCounters& counters);

}  // namespace gdvr
