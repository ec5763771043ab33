#include "core/gradient/gpt_integrator.h"

#include <chrono>

#include "core/gradient/gradient_tracer.h"
#include "core/render/perspective_camera.h"
#include "core/render/tile_scheduler.h"
#include "core/temporal/replay_map.h"

namespace gdvr {

Expected<GptFrameResult> render_frame_gpt(const FrameScene& scene, const FrameRenderSettings& settings,
                                          const GptSettings& gpt, uint32_t frame, const FrameRenderControl& control,
                                          const TemporalShiftTarget* temporal, const ReplayMap* replay) {
  const int w = settings.width, h = settings.height;
  if (w <= 0 || h <= 0) return invalid_argument("render resolution must be positive");
  if (settings.spp <= 0) return invalid_argument("spp must be positive");
  if (replay && (replay->width != w || replay->height != h || replay->sources.size() != size_t(w) * size_t(h)))
    return invalid_argument("replay map is " + std::to_string(replay->width) + "x" + std::to_string(replay->height) +
                            ", the frame " + std::to_string(w) + "x" + std::to_string(h));
  GDVR_RETURN_IF_ERROR(gpt.validate());
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };

  PerspectiveCamera camera(scene.scene().camera, w, h);
  GradientFilm film(w, h, temporal != nullptr, gpt.pair_primal);
  std::atomic<uint64_t> rays{0}, invalid{0}, shifts{0}, failures{0}, temporal_rays{0};
  int spp_done = 0;

  // ---- Emitters seen directly: their own stratified pass (first, so a time
  // budget includes it); it replaces the base paths' `direct` except where it
  // leaves pixels to them (DirectEmissionSettings::uniform_from_paths) ----
  auto direct = render_frame_direct(scene, settings, control);
  if (!direct.ok()) return direct.status();
  rays += direct->rays;
  invalid += direct->invalid_samples;
  const bool timed = settings.time_budget_s > 0;
  const double sampling_start = elapsed();
  while (true) {
    const int first = spp_done, count = settings.spp;
    const double pass_start = elapsed();
    Status st = run_tiles(w, h, pass_tile_options(settings, control, start), [&](const Tile& tile) {
      GradientTracer tracer(scene, camera, w, h, settings.path, gpt, settings.seed, frame);
      tracer.set_temporal_target(temporal);
      tracer.set_replay_map(replay);
      GradientSample gs;
      uint64_t tile_shifts = 0, tile_failures = 0;
      // Sample-major: one sample index over the whole tile at a time, so that
      // base paths and offsets can share the index's camera-ray hits.
      for (int s = first; s < first + count; ++s) {
        tracer.begin_sample(tile, uint32_t(s));
        for (int y = tile.y0; y < tile.y1; ++y)
          for (int x = tile.x0; x < tile.x1; ++x) {
            tracer.sample(x, y, &gs);
            film.add(x, y, uint32_t(s), gs);
            tile_shifts += uint64_t(gs.shifts);
            tile_failures += uint64_t(gs.failures);
          }
      }
      rays += tracer.counters().rays;
      temporal_rays += tracer.temporal_rays();
      invalid += tracer.counters().invalid_samples;
      shifts += tile_shifts;
      failures += tile_failures;
    });
    if (!st.ok()) return st;
    spp_done += count;
    const double last_pass_seconds = elapsed() - pass_start;
    if (!timed || elapsed() + last_pass_seconds > settings.time_budget_s) break;
  }
  const double sampling_seconds = elapsed() - sampling_start;

  GptFrameResult result;
  result.buffers = film.resolve(spp_done);
  if (gpt.pair_primal) {
    // The reconstruction (and the `primal` layer) get the pair primal.
    result.buffers.primal = std::move(result.buffers.pair_primal);
    result.buffers.primal_var = std::move(result.buffers.pair_primal_var);
    result.buffers.pair_primal = Image();
    result.buffers.pair_primal_var = Image();
  }
  if (!direct->direct.empty()) result.buffers.direct = merge_direct_estimates(std::move(*direct), result.buffers.direct);
  result.spp = spp_done;
  result.rays = rays;
  result.temporal_rays = temporal_rays;
  result.invalid_samples = invalid;
  result.shift_failure_rate = shifts > 0 ? double(failures) / double(shifts) : 0.0;
  result.seconds = elapsed();
  result.sampling_seconds = sampling_seconds;
  return result;
}

}  // namespace gdvr
