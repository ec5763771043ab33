// gdvr-bench: the path tracer's ray throughput against the limit of bare ray
// casting on this machine.
//
//   gdvr-bench SCENE.xml [--spp N] [--threads N] [--runs N] [--paths-in-flight N] [--param NAME=VALUE ...]
//
// 1. Renders the scene with the path tracer (all shading, sampling, MIS) and
//    reports rays/s.
// 2. Records every ray that render traced (same scene, seed, spp, tiles),
//    in the order the path tracer cast them and in path order, then replays
//    exactly those rays through the accelerator's bare Embree calls (no
//    shading), on the same thread count, three ways: one ray per call
//    (rtcIntersect1 / rtcOccluded1) in cast order and in path order, and in
//    cast order as the streams the path tracer cast them in (rtcIntersect1M /
//    rtcOccluded1M), each with the coherence flag the path tracer gave it
//    (its camera rays go as coherent streams), so the limit gains whatever
//    the flag gains.
// The ratio of (1) to the fastest replay in (2) is the share of the
// ray-casting limit the path tracer reaches. Each figure is the median of --runs runs measured in the same process.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "core/render/vector_batch.h"
#include "core/render/frame_scene.h"
#include "core/render/path_batch.h"
#include "core/render/perspective_camera.h"
#include "core/render/pt_integrator.h"
#include "core/render/tile_scheduler.h"
#include "core/scene/mitsuba_loader.h"
#include "core/util/cli_args.h"
#include "core/util/memory_tuning.h"

namespace {

using namespace gdvr;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The rays of the samples render_frame_pt traces (single pass, same tiles),
// in one of two orders:
//  - cast order: as the path tracer casts them, a batch of paths at a time
//    (path_batch.h), which is what the render's rays/s measures;
//  - path order: each path's rays in turn (trace_path), which keeps a path's
//    consecutive rays near each other in the BVH and so is faster to cast bare.
// The bare limit is the faster of the two.
enum class RayOrder { kCast, kPath };

std::vector<RecordedRay> record_rays(const FrameScene& scene, const FrameRenderSettings& s, RayOrder order) {
  PerspectiveCamera camera(scene.scene().camera, s.width, s.height);
  std::vector<RecordedRay> rays;
  PathCounters counters;
  counters.ray_log = &rays;
  TileRunOptions one_thread;  // one thread: the log is not shared
  one_thread.threads = 1;
  one_thread.tile_size = s.tile_size;
  Status st = run_tiles(s.width, s.height, one_thread, [&](const Tile& tile) {
    if (order == RayOrder::kCast) {
      trace_tile_samples(scene, s.path, camera, s.seed, 0, tile, 0, s.spp, s.paths_in_flight, counters,
                         [](int, int, const PathSample&) {});
      return;
    }
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x)
        for (int i = 0; i < s.spp; ++i) {
          Sampler sampler(s.seed, 0, uint32_t(x), uint32_t(y), uint32_t(i));
          Vec2f j = sampler.next_2d();
          trace_path(scene, s.path, camera.generate_ray({float(x) + j.x, float(y) + j.y}), sampler, counters);
        }
  });
  if (!st.ok()) std::fprintf(stderr, "gdvr-bench: recording: %s\n", st.to_string().c_str());
  return rays;
}

// What a recorded closest-hit query tested.

// Casts `rays` one per call through the accelerator's bare Embree calls;
// returns rays/s.
double replay_single(const Accelerator& accel, const std::vector<RecordedRay>& rays, tbb::task_arena& arena) {
  std::atomic<uint64_t> hits{0};
  auto t0 = std::chrono::steady_clock::now();
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 4096), [&](const tbb::blocked_range<size_t>& br) {
      uint64_t local = 0;
      RayHit hit;
      for (size_t i = br.begin(); i != br.end(); ++i) {
        const RecordedRay& rr = rays[i];
        if (rr.shadow) local += accel.occluded(rr.ray.o, rr.ray.d, rr.ray.tmin, rr.ray.tmax);
        else local += accel.intersect(rr.ray.o, rr.ray.d, rr.ray.tmin, rr.ray.tmax, &hit, rr.set);
      }
      hits += local;  // keeps the loop from being optimised away
    });
  });
  const double rate = double(rays.size()) / seconds_since(t0);
  if (hits.load() == 0) std::fprintf(stderr, "gdvr-bench: warning: no ray hit anything\n");
  return rate;
}

bool rays_differ_in_kind(const std::vector<RecordedRay>& rays, size_t begin, size_t end) {
  for (size_t i = begin + 1; i < end; ++i)
    if (rays[i].shadow != rays[begin].shadow || rays[i].set != rays[begin].set ||
        rays[i].coherent != rays[begin].coherent)
      return true;
  return false;
}

// [begin, end) of each stream of `rays` (RecordedRay::stream); a ray cast
// on its own is a group of one.
std::vector<std::pair<size_t, size_t>> stream_groups(const std::vector<RecordedRay>& rays) {
  std::vector<std::pair<size_t, size_t>> groups;
  for (size_t i = 0; i < rays.size();) {
    size_t end = i + 1;
    if (rays[i].stream != 0)
      while (end < rays.size() && rays[end].stream == rays[i].stream) ++end;
    groups.emplace_back(i, end);
    i = end;
  }
  return groups;
}

// Casts each group of `rays` as one stream query, as the path tracer did;
// returns rays/s.
double replay_streams(const Accelerator& accel, const std::vector<RecordedRay>& rays,
                      const std::vector<std::pair<size_t, size_t>>& groups, tbb::task_arena& arena) {
  std::atomic<uint64_t> hits{0};
  auto t0 = std::chrono::steady_clock::now();
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, groups.size(), 64), [&](const tbb::blocked_range<size_t>& br) {
      uint64_t local = 0;
      RayStreamBuffer buffer;  // as the path tracer casts them (path_stages.h)
      for (size_t g = br.begin(); g != br.end(); ++g) {
        const auto [begin, end] = groups[g];
        const int n = int(end - begin);
        for (int k = 0; k < n; ++k) set_stream_ray(buffer, k, rays[begin + size_t(k)].ray);
        if (rays[begin].shadow) {
          accel.occluded_stream(buffer, n);
          for (int k = 0; k < n; ++k) local += buffer.occluded(k);
        } else {
          accel.intersect_stream(buffer, n, rays[begin].set,
                                 rays[begin].coherent ? RayCoherence::kCoherent : RayCoherence::kIncoherent);
          for (int k = 0; k < n; ++k) local += buffer.found(k);
        }
      }
      hits += local;
    });
  });
  const double rate = double(rays.size()) / seconds_since(t0);
  if (hits.load() == 0) std::fprintf(stderr, "gdvr-bench: warning: no ray hit anything\n");
  return rate;
}

}  // namespace

int main(int argc, char** argv) {
  gdvr::retain_freed_memory_for_reuse();  // core/util/memory_tuning.h: batch tool
  if (argc < 2) {
    std::fprintf(stderr, "usage: gdvr-bench SCENE.xml [--spp N] [--threads N] [--runs N] [--paths-in-flight N] [--param NAME=VALUE ...]\n");
    return 2;
  }
  std::string path = argv[1];
  int spp = 16, threads = 0, runs = 3, paths_in_flight = kPathBatch;
  LoadOptions load;
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    if (i + 1 >= argc) { std::fprintf(stderr, "gdvr-bench: %s needs a value\n", a.c_str()); return 2; }
    std::string v = argv[++i];
    if (a == "--spp") spp = int(tools::int_option("gdvr-bench", a, v, 1, 1 << 20));
    else if (a == "--threads") threads = int(tools::int_option("gdvr-bench", a, v, 1, 1024));
    else if (a == "--runs") runs = int(tools::int_option("gdvr-bench", a, v, 1, 1000));
    else if (a == "--paths-in-flight") paths_in_flight = int(tools::int_option("gdvr-bench", a, v, 1, kPathBatch));
    else if (a == "--param") {
      if (!tools::parse_param(v, &load.params)) { std::fprintf(stderr, "gdvr-bench: --param: expected NAME=VALUE\n"); return 2; }
    } else { std::fprintf(stderr, "gdvr-bench: unknown option %s\n", a.c_str()); return 2; }
  }
  auto scene = load_mitsuba_scene(path, load);
  if (!scene.ok()) { std::fprintf(stderr, "gdvr-bench: %s\n", scene.status().to_string().c_str()); return 1; }
  auto fs = FrameScene::create(scene.value(), {});
  if (!fs.ok()) { std::fprintf(stderr, "gdvr-bench: %s\n", fs.status().to_string().c_str()); return 1; }
  const FrameScene& frame_scene = *fs.value();

  FrameRenderSettings s;
  s.width = scene->defaults.width;
  s.height = scene->defaults.height;
  s.spp = spp;
  s.seed = 1;
  s.threads = threads;
  s.paths_in_flight = paths_in_flight;
  s.path.max_depth = scene->defaults.max_depth;
  s.path.rr_depth = scene->defaults.rr_depth;
  const int thread_count = resolve_thread_count(threads);

  // Record the exact rays the render traces, then alternate path-tracer and
  // bare runs so that both see the same machine load (this machine is shared).
  const std::vector<RecordedRay> cast_order = record_rays(frame_scene, s, RayOrder::kCast);
  const std::vector<RecordedRay> path_order = record_rays(frame_scene, s, RayOrder::kPath);
  // The same paths either way, so the same rays, but for the rare camera ray
  // that meets two triangles at exactly the same t (coplanar overlapping
  // faces, as under the Cornell box's light): the batches' coherent camera
  // streams may report the other one (RayCoherence in accelerator.h), and the
  // path goes on from there. Rates are per ray, so a few such paths do not
  // matter; more than 1e-4 of the rays would mean the recordings went wrong.
  const double count_difference =
      std::abs(double(cast_order.size()) - double(path_order.size())) / double(std::max<size_t>(1, cast_order.size()));
  if (cast_order.empty() || count_difference > 1e-4) {
    std::fprintf(stderr, "gdvr-bench: the two recordings differ (%zu / %zu rays)\n", cast_order.size(),
                 path_order.size());
    return 1;
  }
  const Accelerator& accel = frame_scene.accelerator();
  tbb::task_arena arena(thread_count);
  const std::vector<std::pair<size_t, size_t>> groups = stream_groups(cast_order);
  for (const auto& [begin, end] : groups)
    if (end - begin > size_t(kPathBatch) || (end - begin > 1 && rays_differ_in_kind(cast_order, begin, end))) {
      std::fprintf(stderr, "gdvr-bench: a recorded stream is longer than %d rays or mixes kinds\n", kPathBatch);
      return 1;
    }
  std::vector<double> pt_rate, single_rate, cast_rate, path_rate, stream_rate, ratios, gains;
  uint64_t pt_rays = 0;
  for (int r = 0; r < runs; ++r) {
    auto result = render_frame_pt(frame_scene, s, 0, {});
    if (!result.ok()) { std::fprintf(stderr, "gdvr-bench: %s\n", result.status().to_string().c_str()); return 1; }
    pt_rays = result->rays;
    pt_rate.push_back(double(result->rays) / result->seconds);
    // The same render one path at a time: what the batches gain, same run.
    FrameRenderSettings single = s;
    single.paths_in_flight = 1;
    auto one = render_frame_pt(frame_scene, single, 0, {});
    if (!one.ok()) { std::fprintf(stderr, "gdvr-bench: %s\n", one.status().to_string().c_str()); return 1; }
    single_rate.push_back(double(one->rays) / one->seconds);
    gains.push_back(pt_rate.back() / single_rate.back());
    cast_rate.push_back(replay_single(accel, cast_order, arena));
    path_rate.push_back(replay_single(accel, path_order, arena));
    stream_rate.push_back(replay_streams(accel, cast_order, groups, arena));
    ratios.push_back(pt_rate.back() / std::max({cast_rate.back(), path_rate.back(), stream_rate.back()}));
  }

  std::printf("scene            %s\n", path.c_str());
  std::printf("resolution       %dx%d, %d spp, %d threads, %d runs (medians)\n", s.width, s.height, spp, thread_count, runs);
  std::printf("rays per render  %llu (recorded %zu)\n", (unsigned long long)pt_rays, cast_order.size());
  const std::string scalar_why = why_no_vector_batch(frame_scene, s.path, s.paths_in_flight);
  const std::string kernel = scalar_why.empty() ? std::string("vector batch, ") + vector_kernels().front().isa +
                                                      " kernel"
                                                : "scalar batch: the vector batch's kernel is left out, " + scalar_why;
  std::printf("path tracer      %.2f Mrays/s, %d paths in flight per thread (%s)\n", median(pt_rate) * 1e-6,
              s.paths_in_flight, kernel.c_str());
  std::printf("  one at a time  %.2f Mrays/s (batched / one at a time: %.3f, median of per-run ratios)\n",
              median(single_rate) * 1e-6, median(gains));
  std::printf("bare Embree      %.2f Mrays/s as the tracer's streams (%zu); single rays: %.2f in cast order, %.2f in path order\n",
              median(stream_rate) * 1e-6, groups.size(), median(cast_rate) * 1e-6, median(path_rate) * 1e-6);
  std::printf("ratio            %.3f (median of per-run ratios to the fastest bare replay)\n", median(ratios));
  double loadavg[1] = {0};
  if (getloadavg(loadavg, 1) == 1) std::printf("load average     %.2f\n", loadavg[0]);
  return 0;
}
