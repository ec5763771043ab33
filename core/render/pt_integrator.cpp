#include "core/render/pt_integrator.h"

#include <chrono>
#include <memory>
#include <vector>

#include "core/render/path_batch.h"
#include "core/render/perspective_camera.h"
#include "core/render/tile_scheduler.h"

namespace gdvr {
namespace {

// Per-pixel running sums in double so that thousands of samples of very
// different magnitude accumulate without loss. Left uninitialised: each tile
// zeroes its own pixels in its first pass, so the frame's sums (72 bytes a
// pixel) are not first written, and faulted in, by one thread.
struct PixelSums {
  double sum[3], sum_sq[3], direct[3];
};

}  // namespace

Expected<DirectEmissionResult> render_frame_direct(const FrameScene& scene, const FrameRenderSettings& settings,
                                                   const FrameRenderControl& control) {
  if (!settings.direct.enabled()) return DirectEmissionResult{};
  PerspectiveCamera camera(scene.scene().camera, settings.width, settings.height);
  return render_direct_emission(scene, camera, settings.width, settings.height, settings.direct, settings.seed,
                                kDirectEmissionStream, settings.path, settings.threads, control.cancel);
}

TileRunOptions pass_tile_options(const FrameRenderSettings& settings, const FrameRenderControl& control,
                                 std::chrono::steady_clock::time_point frame_start) {
  TileRunOptions opts;
  opts.threads = settings.threads;
  opts.tile_size = settings.tile_size;
  opts.cancel = control.cancel;
  if (control.on_progress) {
    const double budget = settings.time_budget_s;
    opts.on_progress = [budget, frame_start, report = control.on_progress](double f) {
      const double spent = std::chrono::duration<double>(std::chrono::steady_clock::now() - frame_start).count();
      report(budget > 0 ? std::min(1.0, spent / budget) : f);
    };
  }
  return opts;
}

Expected<FrameRenderResult> render_frame_pt(const FrameScene& scene, const FrameRenderSettings& settings,
                                            uint32_t frame, const FrameRenderControl& control) {
  const int w = settings.width, h = settings.height;
  if (w <= 0 || h <= 0) return invalid_argument("render resolution must be positive");
  if (settings.spp <= 0) return invalid_argument("spp must be positive");
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };

  PerspectiveCamera camera(scene.scene().camera, w, h);
  std::unique_ptr<PixelSums[]> sums(new PixelSums[size_t(w) * size_t(h)]);
  std::atomic<uint64_t> rays{0}, invalid{0};
  int spp_done = 0;

  // ---- Emitters seen directly: their own stratified pass (first, so a time
  // budget includes it); the paths then leave out emission at depth 0, so the
  // pass must estimate every pixel itself ----
  FrameRenderSettings direct_settings = settings;
  direct_settings.direct.uniform_from_paths = false;
  auto direct = render_frame_direct(scene, direct_settings, control);
  if (!direct.ok()) return direct.status();
  Image direct_pass = std::move(direct->direct);
  rays += direct->rays;
  invalid += direct->invalid_samples;
  PathTracerSettings path = settings.path;
  if (!direct_pass.empty()) path.hide_emitters = true;

  // Passes: one pass of `spp` samples in spp mode; in time-budget mode passes
  // of `spp` samples each until the next pass would overrun the budget.
  const bool timed = settings.time_budget_s > 0;
  const double sampling_start = elapsed();
  double last_pass_seconds = 0;
  while (true) {
    const int first = spp_done, count = settings.spp;
    const double pass_start = elapsed();
    Status st = run_tiles(w, h, pass_tile_options(settings, control, start), [&](const Tile& tile) {
      if (first == 0)
        for (int y = tile.y0; y < tile.y1; ++y)
          for (int x = tile.x0; x < tile.x1; ++x) sums[size_t(y) * w + x] = PixelSums{};
      PathCounters counters;
      trace_tile_samples(scene, path, camera, settings.seed, frame, tile, first, count, settings.paths_in_flight,
                         counters,
                         [&](int x, int y, const PathSample& ls) {
                           PixelSums& ps = sums[size_t(y) * w + x];
                           for (int c = 0; c < 3; ++c) {
                             ps.sum[c] += ls.radiance[c];
                             ps.sum_sq[c] += double(ls.radiance[c]) * ls.radiance[c];
                             ps.direct[c] += ls.direct[c];
                           }
                         });
      rays += counters.rays;
      invalid += counters.invalid_samples;
    });
    if (!st.ok()) return st;
    spp_done += count;
    last_pass_seconds = elapsed() - pass_start;
    if (!timed || elapsed() + last_pass_seconds > settings.time_budget_s) break;
  }
  const double sampling_seconds = elapsed() - sampling_start;

  FrameRenderResult result;
  result.color = Image(w, h, 3);
  result.direct = Image(w, h, 3);
  result.variance = Image(w, h, 3);
  const double n = spp_done;
  // The means and variances, tile by tile on the render's threads (not
  // cancellable: the samples are all in).
  TileRunOptions finish_opts;
  finish_opts.threads = settings.threads;
  finish_opts.tile_size = settings.tile_size;
  Status finished = run_tiles(w, h, finish_opts, [&](const Tile& tile) {
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        const PixelSums& ps = sums[size_t(y) * w + x];
        for (int c = 0; c < 3; ++c) {
          double mean = ps.sum[c] / n;
          result.color.at(x, y, c) = float(mean);
          result.direct.at(x, y, c) = float(ps.direct[c] / n);
          double var = n > 1 ? std::max(0.0, (ps.sum_sq[c] / n - mean * mean) / (n - 1)) : 0.0;
          result.variance.at(x, y, c) = float(var);
        }
      }
  });
  if (!finished.ok()) return finished;
  if (!direct_pass.empty()) {
    // The pass's own variance is not measured (it is far below the paths').
    for (size_t k = 0; k < result.color.data().size(); ++k) result.color.data()[k] += direct_pass.data()[k];
    result.direct = std::move(direct_pass);
  }
  result.spp = spp_done;
  result.rays = rays;
  result.invalid_samples = invalid;
  result.seconds = elapsed();
  result.sampling_seconds = sampling_seconds;
  return result;
}

}  // namespace gdvr
