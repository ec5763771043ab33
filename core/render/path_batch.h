// Path tracing a batch of independent paths stage by stage (path_stages.h):
// every live path's closest-hit ray, then every path's shading, then every
// pending shadow ray, then the next bounce. One path at a time, each vertex's
// shading is a chain of dependent square roots and divisions between two ray
// casts that the core cannot overlap with anything; a batch gives it the
// other paths' independent work to overlap. And the batch's rays of one kind
// go to Embree as one stream, which it traces in SIMD packets, faster per
// ray than one at a time (docs/renderer.md, "Rays in streams"). Each path's numbers and
// arithmetic are those of trace_path(), and the stream's hits those of single
// casts, so its radiance is the same bit for bit (but where its camera ray,
// cast in a coherent stream, meets two triangles at exactly the same t:
// RayCoherence in accelerator.h).
#pragma once

#include <cstdint>
#include <functional>

#include "core/render/path_stages.h"
#include "core/render/perspective_camera.h"
#include "core/render/tile_scheduler.h"

namespace gdvr {

// Advances paths[0..n) until each has finished; out[i] is path i's sample.
void trace_path_batch(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths, int n,
                      PathCounters& counters, PathSample* out);

// Samples [first_sample, first_sample + count) of every pixel of `tile`,
// traced in batches of `paths_in_flight` (1..kPathBatch; 1 is one path at a
// time, for benchmarks); `add` receives them in the order of trace_path's loop
// (rows, pixels, samples), so running sums come out bit-identical.
void trace_tile_samples(const FrameScene& scene, const PathTracerSettings& settings, const PerspectiveCamera& camera,
                        uint64_t seed, uint32_t frame, const Tile& tile, int first_sample, int count,
                        int paths_in_flight, PathCounters& counters, const std::function<void(int x, int y, const PathSample&)>& add);

}  // namespace gdvr
