#include "core/temporal/tgpt_frame.h"

#include <algorithm>
#include <chrono>
#include <memory>

#include "core/temporal/replay_map.h"

namespace gdvr {
namespace {

// A temporal shift's target frame with the camera and shape motions it needs
// (owned here; TemporalShiftTarget points into it).
class TemporalTarget {
 public:
  TemporalTarget() = default;
  TemporalTarget(const FrameScene& other, const Scene& at_t, const Scene& at_other, int width, int height)
      : camera_(std::make_unique<PerspectiveCamera>(at_other.camera, width, height)),
        motion_(std::make_unique<ShapeMotion>(at_t, at_other)) {
    target_.scene = &other;
    target_.camera = camera_.get();
    target_.motion = motion_.get();
  }
  const TemporalShiftTarget* target() const { return target_.scene ? &target_ : nullptr; }

 private:
  std::unique_ptr<PerspectiveCamera> camera_;
  std::unique_ptr<ShapeMotion> motion_;
  TemporalShiftTarget target_;
};

}  // namespace

Expected<TgptFrameRender> render_tgpt_frame(const FrameScene& scene, const FrameRenderSettings& render,
                                            const TgptSettings& settings, TgptPassStreams streams,
                                            const TgptNeighbourhood& nb, const GradientFilmBuffers* reuse_a,
                                            const FrameRenderControl& control, const TgptPassSizes& sizes) {
  GDVR_RETURN_IF_ERROR(settings.validate());
  if (!nb.at_t) return invalid_argument("render_tgpt_frame: no scene description for the frame");
  if (reuse_a && (!nb.prev || nb.to_prev.any()))
    return failed_precondition("render_tgpt_frame: pass A can only be reused across a static frame pair");
  const auto start = std::chrono::steady_clock::now();
  TgptFrameRender out;
  // ---- Direct light: one stratified pass for the frame, the same jitter in
  // every frame (first, so that a time budget includes it); the pixels it
  // leaves to the paths are filled from both passes at the end ----
  auto direct = render_frame_direct(scene, render, control);
  if (!direct.ok()) return direct.status().with_context("direct light: ");
  out.rays += direct->rays;
  out.invalid_samples += direct->invalid_samples;

  // The passes take the direct light from their own camera samples (free
  // there); the pass above replaces it.
  FrameRenderSettings half = render;
  half.direct = DirectEmissionSettings{0, 0};
  half.spp = tgpt_pass_spp(render.spp);
  half.time_budget_s = 0;
  FrameRenderSettings settings_a = half;
  if (sizes.a_spp > 0) settings_a.spp = sizes.a_spp;
  else if (sizes.a_seconds > 0) settings_a.time_budget_s = sizes.a_seconds;

  // ---- Path-space temporal shift (reconnect): pass A's base paths go to the
  // previous frame, pass B's to the next, where the pair changes ----
  const bool reconnect = settings.temporal_shift == TemporalShiftMapping::kReconnect;
  TemporalTarget backward, forward;
  if (reconnect && nb.prev && nb.to_prev.any()) {
    if (!nb.prev_scene)
      return failed_precondition("render_tgpt_frame: temporal_shift reconnect needs the previous frame's scene");
    backward = TemporalTarget(*nb.prev_scene, *nb.at_t, *nb.prev, render.width, render.height);
  }
  if (reconnect && nb.next && nb.to_next.any()) {
    if (!nb.next_scene)
      return failed_precondition("render_tgpt_frame: temporal_shift reconnect needs the next frame's scene");
    forward = TemporalTarget(*nb.next_scene, *nb.at_t, *nb.next, render.width, render.height);
  }

  // ---- Motion towards the previous frame, first: the compensated replay
  // (TgptSettings::motion_compensation) renders pass A along it ----
  const bool prev_changes = nb.prev && nb.to_prev.any();
  if (prev_changes) {
    out.backward = compute_motion_field(scene, *nb.at_t, *nb.prev, render.width, render.height, render.threads);
    out.rays += out.backward.rays;
    out.temporal_rays += out.backward.rays;
  }

  // ---- Pass A (stream s(t)): the replayed offset of the previous frame's pass B ----
  FrameRenderControl control_a = control, control_b = control;
  if (control.on_progress) {
    control_a.on_progress = [&](double f) { control.on_progress(0.5 * f); };
    control_b.on_progress = [&](double f) { control.on_progress(0.5 + 0.5 * f); };
  }
  double a_seconds = 0;
  if (reuse_a) {
    out.a = *reuse_a;
    out.reused_pass_a = true;
    out.a_spp = settings_a.spp;  // the caller's count for it (the previous pass B's)
  } else {
    // Each pixel replays the stream of the previous frame's pixel its surface
    // came from (a copied pass A needs none: a static pair does not move).
    ReplayMap replay;
    if (prev_changes && settings.compensates_motion()) replay = build_replay_map(out.backward.offsets);
    auto a = render_frame_gpt(scene, settings_a, settings.gpt, streams.a, control_a, backward.target(),
                              replay.empty() ? nullptr : &replay);
    if (!a.ok()) return a.status().with_context("pass A: ");
    out.a = std::move(a->buffers);
    out.rays += a->rays;
    out.invalid_samples += a->invalid_samples;
    out.a_spp = a->spp;
    a_seconds = a->sampling_seconds;
    if (prev_changes) out.temporal_rays += reconnect ? a->temporal_rays : a->rays;
  }
  // ---- Pass B (stream s(t_next)): replayed by the next frame's pass A ----
  FrameRenderSettings settings_b = half;
  settings_b.spp = sizes.b_spp ? sizes.b_spp(out.reused_pass_a ? 0 : out.a_spp, a_seconds)
                               : (sizes.a_spp > 0 || sizes.a_seconds > 0 ? out.a_spp : half.spp);
  if (settings_b.spp <= 0) return invalid_argument("render_tgpt_frame: pass B's spp must be positive");
  auto b = render_frame_gpt(scene, settings_b, settings.gpt, streams.b, control_b, forward.target());
  if (!b.ok()) return b.status().with_context("pass B: ");
  out.b = std::move(b->buffers);
  out.rays += b->rays;
  out.temporal_rays += b->temporal_rays;
  out.invalid_samples += b->invalid_samples;
  out.b_spp = b->spp;
  out.spp = out.a_spp + out.b_spp;
  out.sampling_seconds = a_seconds + b->sampling_seconds;

  // ---- Motion towards the next frame, only where it differs (the backward
  // field is above) ----
  if (nb.next && nb.to_next.any()) {
    out.forward = compute_motion_field(scene, *nb.at_t, *nb.next, render.width, render.height, render.threads);
    out.rays += out.forward.rays;
    out.temporal_rays += out.forward.rays;
  }
  if (!direct->direct.empty())
    out.direct = merge_direct_estimates(std::move(*direct), out.a.direct, &out.b.direct);
  if (!nb.next)
    out.left_out.push_back("temporal offsets: last frame of the shot (no next frame)");
  else if (!nb.to_next.any())
    out.left_out.push_back("temporal offsets and motion vectors: static frame pair (nothing changes towards the next frame)");
  if (out.reused_pass_a)
    out.left_out.push_back("pass A: equals the previous frame's pass B (static pair, same random numbers), copied");
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace gdvr
