#include "core/job/integrators/tgpt_runner.h"

#include <algorithm>
#include <chrono>
#include <memory>

#include "core/job/integrators/gradient_domain_frame.h"
#include "core/recon/reconstruct.h"
#include "core/render/feature_buffers.h"
#include "core/temporal/change_detection.h"
#include "core/temporal/pass_schedule.h"
#include "core/temporal/temporal_buffers.h"
#include "core/temporal/tgpt_frame.h"

namespace gdvr {

Expected<std::unique_ptr<TgptRunner>> TgptRunner::create(const JobSpec& job, std::vector<int> job_frames) {
  TgptSettings s;
  s.gpt = TgptSettings::gpt_defaults_for(job.shift);
  s.temporal_shift = job.temporal_shift;
  s.data_term = job.reconstruction.data_term;
  s.recon = job_recon_settings(job.reconstruction, s.recon);
  s.window = job.reconstruction.window;
  GDVR_RETURN_IF_ERROR(s.validate().with_context("job: "));
  return std::unique_ptr<TgptRunner>(new TgptRunner(std::move(s), job.reconstruction.clamp_negative, std::move(job_frames)));
}

TgptRunner::TgptRunner(TgptSettings settings, bool clamp_negative, std::vector<int> job_frames)
    : settings_(std::move(settings)), clamp_negative_(clamp_negative), windows_(settings_, std::move(job_frames)) {}

// Two half passes, motion fields where the pair changes.
Status TgptRunner::render(const FrameRenderContext& context, int frame, FrameBuffers* out) {
  const std::vector<int>& frames = windows_.frames();
  const int pos = windows_.position(frame);
  if (pos < 0) return invalid_argument("frame " + std::to_string(frame) + " is not in the job's frame range");
  // The neighbours' animated descriptions (copies share meshes and textures).
  Scene prev_desc, next_desc;
  TgptNeighbourhood nb;
  nb.at_t = &context.description;
  if (pos > 0) {
    GDVR_RETURN_IF_ERROR(context.describe_frame(frames[size_t(pos) - 1], &prev_desc));
    nb.prev = &prev_desc;
    nb.to_prev = detect_changes(prev_desc, context.description);
  }
  if (size_t(pos) + 1 < frames.size()) {
    GDVR_RETURN_IF_ERROR(context.describe_frame(frames[size_t(pos) + 1], &next_desc));
    nb.next = &next_desc;
    nb.to_next = detect_changes(context.description, next_desc);
  }
  // The path-space temporal shift traces in the neighbours' scenes: keep one
  // FrameScene per side, moved to the neighbour's time (built once).
  if (settings_.temporal_shift == TemporalShiftMapping::kReconnect) {
    auto scene_at = [&](const Scene& desc, std::unique_ptr<FrameScene>* slot) -> Status {
      if (*slot) return (*slot)->update(desc);
      auto fs = FrameScene::create(desc, context.animated_shapes);
      if (!fs.ok()) return fs.status();
      *slot = std::move(fs.value());
      return Status::Ok();
    };
    if (nb.prev && nb.to_prev.any()) {
      GDVR_RETURN_IF_ERROR(scene_at(prev_desc, &scene_prev_));
      nb.prev_scene = scene_prev_.get();
    }
    if (nb.next && nb.to_next.any()) {
      GDVR_RETURN_IF_ERROR(scene_at(next_desc, &scene_next_));
      nb.next_scene = scene_next_.get();
    }
  }
  // Pass A of t replays pass B of t−1 (same stream): it takes B's count, so
  // that dt = A_t − B_{t−1} is a correlated difference, when this process
  // rendered frame t−1 just before. Across a static pair the scene is the
  // same too, so the pass is the same image: copied, not rendered.
  const bool follows_b = pos > 0 && last_b_frame_ == frames[size_t(pos) - 1];
  const GradientFilmBuffers* reuse = nullptr;
  if (follows_b && !nb.to_prev.any() && last_b_kept_) reuse = &last_b_;
  TgptPassSizes sizes;
  if (follows_b) sizes.a_spp = last_b_spp_;
  double a_seconds = 0;
  if (FrameTimeBudget* budget = context.budget) {
    const int unit = tgpt_pass_spp(context.settings.spp);
    // The first frame of a process: pass A pairs with nothing here, and
    // runs against the clock to measure what a sample costs.
    if (!follows_b) {
      if (budget->has_sample_cost())
        sizes.a_spp = budget->take_count(budget->samples_in(budget->sampling_seconds()) / 2, unit);
      else
        sizes.a_seconds = std::max(0.5 * budget->sampling_seconds(), 1e-6);
    }
    // Pass B: half the frame's samples, steady from frame to frame, whatever
    // pass A took (a count that made up for A would swing: 3, 7, 3, 7, ...).
    // When the next frame copies it (static pair), it is all the samples.
    const double share = nb.next && !nb.to_next.any() ? 1.0 : 0.5;
    const double allowance = budget->sampling_seconds();
    sizes.b_spp = [budget, unit, share, allowance, &a_seconds](int a_spp, double seconds) {
      budget->record_sampling(a_spp, seconds);
      a_seconds = seconds;
      return budget->take_count(budget->samples_in(allowance) * share, unit);
    };
  }
  auto result = render_tgpt_frame(context.scene, context.settings, settings_, tgpt_pass_streams(frames, size_t(pos)),
                                  nb, reuse, context.control, sizes);
  if (!result.ok()) return result.status();
  TgptFrameRender& r = result.value();
  if (context.budget) context.budget->record_sampling(r.b_spp, r.sampling_seconds - a_seconds);
  last_b_frame_ = frame;
  last_b_spp_ = r.b_spp;
  last_b_kept_ = nb.next && !nb.to_next.any();
  if (last_b_kept_) last_b_ = r.b;
  else last_b_ = GradientFilmBuffers{};
  FrameStats& st = out->stats;
  record_render_stats(r, "non-finite samples or gradients dropped", &st);
  st.temporal_rays = r.temporal_rays;
  st.pass_a_spp = r.a_spp;
  st.pass_b_spp = r.b_spp;
  note_unused_glossy_shift(context.scene.scene(), settings_.gpt, &st);
  for (std::string& s : r.left_out) st.left_out.push_back(std::move(s));
  out->layers = tgpt_frame_layers(std::move(r));
  return Status::Ok();
}

double TgptRunner::window_frames_per_frame() const {
  const int n = int(windows_.frames().size());
  if (n == 0) return 0;
  double solved = 0;
  for (const WindowRange& w : shot_windows(n, settings_.window, settings_.hop)) solved += w.end - w.start;
  return solved / n;
}

namespace {

// Stage 2 of a T-GPT frame (its share of the window solves, the temporal
// gradients, the blend) per window frame, over the same of the calibration's
// two-frame window (the first frame's finished buffers twice, joined by zero
// temporal gradients). Measured on the four animations of docs/benchmarks.md
// at 128×128, 12 frames, L1 with the denoised data term, budgets 0.3 and 1 s,
// two runs each: 1.12–1.69, median 1.5. A window's frames no longer fit in
// the cache as two frames' do. The solve of a shot's last window comes after
// its last frame, so what this over- or underestimates is not paid back: in
// those runs at most 0.010 s per frame, 3 % of a 0.3 s budget.
constexpr double kWindowOverCalibrationCost = 1.5;
// The same with a denoised data term, whose L1 solve stops after two rounds
// (ReconSettings::l1_denoised_outer_iterations): the calibration's two frames,
// joined by zero temporal gradients, agree with the denoiser's image sooner
// than a window's frames do. Same measurement: 1.88–2.56, median 2.25.
constexpr double kDenoisedWindowOverCalibrationCost = 2.25;
// Before anything is measured (the first frame's plan only): seconds per
// pixel and window frame of stage 2, same measurement, two cores.
double prior_seconds_per_pixel_frame(ReconMethod method) {
  switch (method) {
    case ReconMethod::kNone: return 0;
    case ReconMethod::kL1: return 1e-5;
    default: return 8e-7;
  }
}

// The buffers a finalize is given, a region at a time: frames held in memory
// are lent or cropped, frames on disk (spilled by run_job, a farm tile task's
// EXRs) are read from their file.
FrameRegionReader region_reader(const std::map<int, FrameBuffers>& buffers) {
  int width = 0, height = 0;
  for (const auto& [f, fb] : buffers) {
    if (fb.on_disk) {
      width = fb.on_disk->width();
      height = fb.on_disk->height();
    } else if (!fb.layers.layers.empty()) {
      width = fb.layers.layers.front().image.width();
      height = fb.layers.layers.front().image.height();
    }
    if (width > 0) break;
  }
  FrameRegionReader r = in_memory_region_reader(width, height, [&buffers](int f) -> const LayeredImage* {
    auto it = buffers.find(f);
    return it == buffers.end() || it->second.on_disk ? nullptr : &it->second.layers;
  });
  r.read = [&buffers, in_memory = std::move(r.read)](int f, const PixelRect& rect)
      -> Expected<std::shared_ptr<const LayeredImage>> {
    auto it = buffers.find(f);
    if (it == buffers.end() || !it->second.on_disk) return in_memory(f, rect);
    auto region = it->second.on_disk->read(rect);
    if (!region.ok()) return region.status().with_context("frame " + std::to_string(f) + ": ");
    return std::shared_ptr<const LayeredImage>(std::make_shared<LayeredImage>(std::move(region.value())));
  };
  return r;
}

}  // namespace

double TgptRunner::finalize_seconds_prior(const FrameRenderSettings& settings, int /*frames*/) const {
  return double(settings.width) * double(settings.height) * window_frames_per_frame() *
         prior_seconds_per_pixel_frame(settings_.recon.method);
}

void TgptRunner::calibrate_stage2(const LayeredImage& layers, FrameTimeBudget* budget) {
  if (solve_calibrated_ || !budget || !budget->pays_stage2()) return;
  solve_calibrated_ = true;
  const auto start = std::chrono::steady_clock::now();
  auto frame = tgpt_gradient_frame(layers, nullptr, gradient_variances_for(settings_.recon.method), settings_.data_term);
  if (!frame.ok()) return;  // the finalize will say what is wrong; the prior stays
  // A two-frame window: the solve's temporal terms and coupling, at two
  // frames' memory (what one frame cannot show).
  const double window_over_calibration =
      frame->data_weight.empty() ? kWindowOverCalibrationCost : kDenoisedWindowOverCalibrationCost;
  GradientFrame first = frame.value();
  for (Term t : {Term::kDt, Term::kDxdt, Term::kDydt})
    first.buffer(t) = Image(first.width(), first.height(), first.channels());
  GradientWindow window;
  window.frames.push_back(std::make_shared<const GradientFrame>(std::move(first)));
  window.frames.push_back(std::make_shared<const GradientFrame>(std::move(frame.value())));
  auto solved = reconstruct(window, settings_.recon);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  budget->record_one_off(seconds);
  if (!solved.ok()) return;
  budget->set_stage2_prior(seconds / 2 * window_over_calibration * window_frames_per_frame());
}

Expected<FrameOutput> TgptRunner::finalize(int frame, const std::map<int, FrameBuffers>& buffers) {
  windows_.solve_only_tiles({});
  auto out = finalize_output(frame, buffers, nullptr);
  // Frames come out in increasing order (a later one, out of order, solves
  // again what it needs): windows ending here are done with.
  if (out.ok()) windows_.release_through(frame);
  return out;
}

Expected<Image> TgptRunner::reconstruct_tiles(int frame, const std::vector<int>& tiles,
                                              const std::map<int, FrameBuffers>& buffers) {
  if (tiles.empty()) return invalid_argument("finalize: no tiles given");
  windows_.solve_only_tiles(tiles);
  auto solved = windows_.reconstruct(frame, region_reader(buffers), nullptr);
  if (!solved.ok()) return solved.status().with_context("frame " + std::to_string(frame) + ": reconstruction: ");
  windows_.release_through(frame);
  return solved;
}

Expected<FrameOutput> TgptRunner::finalize_solved(int frame, const std::map<int, FrameBuffers>& buffers, Image solved) {
  return finalize_output(frame, buffers, &solved);
}

Expected<FrameOutput> TgptRunner::finalize_output(int frame, const std::map<int, FrameBuffers>& buffers,
                                                  Image* solved_elsewhere) {
  const std::vector<int>& frames = windows_.frames();
  const int pos = windows_.position(frame);
  if (pos < 0) return invalid_argument("frame " + std::to_string(frame) + " is not in the job's frame range");
  const int n = int(frames.size());
  const FrameRegionReader reader = region_reader(buffers);
  // The frame and its successor must be here, whole; the windows' other
  // frames only while their window is not solved yet (the cache reports what
  // is missing), and only a tile's region at a time.
  std::shared_ptr<const LayeredImage> held[2];
  for (int k : {0, 1}) {
    if (pos + k >= n) continue;
    const int f = frames[size_t(pos + k)];
    auto whole = reader.read(f, PixelRect::whole(reader.width, reader.height));
    if (!whole.ok()) return whole.status();
    if (!whole.value())
      return failed_precondition("finalize: frame " + std::to_string(frame) + " needs the buffers of frame " +
                                 std::to_string(f));
    held[k] = std::move(whole.value());
  }
  const LayeredImage& layers = *held[0];
  const ImageLayer* direct = layers.find("direct");
  if (!direct) return invalid_argument("finalize: frame buffers lack the 'direct' layer");

  ReconStats recon_stats;
  Image final_image;
  if (solved_elsewhere) {
    if (solved_elsewhere->width() != direct->image.width() || solved_elsewhere->height() != direct->image.height() ||
        solved_elsewhere->channels() != direct->image.channels())
      return invalid_argument("finalize: frame " + std::to_string(frame) + ": the solved image is " +
                              std::to_string(solved_elsewhere->width()) + "x" + std::to_string(solved_elsewhere->height()) +
                              ", its buffers are " + std::to_string(direct->image.width()) + "x" +
                              std::to_string(direct->image.height()));
    final_image = std::move(*solved_elsewhere);
  } else {
    auto solved = windows_.reconstruct(frame, reader, &recon_stats);
    if (!solved.ok()) return solved.status().with_context("frame " + std::to_string(frame) + ": reconstruction: ");
    final_image = std::move(solved.value());
  }
  const int64_t bad_direct = add_direct_clamped(direct->image, clamp_negative_, &final_image);

  FrameOutput out;
  out.frame = frame;
  out.stats = buffers.at(frame).stats;
  out.stats.reconstruct_seconds = recon_stats.seconds;
  if (bad_direct > 0)
    out.stats.left_out.push_back(std::to_string(bad_direct) + " non-finite direct-light values dropped");
  out.image.add("", {"R", "G", "B"}, std::move(final_image));
  auto add_estimate = [&](const char* name) -> Status {
    auto est = tgpt_frame_estimate(layers, name);
    if (!est.ok()) return est.status();
    out.image.add(name, {"R", "G", "B"}, std::move(est.value()));
    return Status::Ok();
  };
  if (n == 1) {
    // A single-frame job never forms temporal buffers: no dt layers.
    for (const char* name : {"primal", "dx", "dy"}) GDVR_RETURN_IF_ERROR(add_estimate(name));
    out.image.layers.push_back(*direct);
    for (const char* name : {"primal_var", "dx_var", "dy_var"}) GDVR_RETURN_IF_ERROR(add_estimate(name));
    if (const ImageLayer* l = layers.find("shift_failure_rate")) out.image.layers.push_back(*l);
    copy_feature_layers(layers, &out.image);
    out.stats.left_out.push_back("temporal gradients and buffers: single-frame job");
    zero_non_finite_layers(&out);
    return out;
  }
  // The frame's own temporal layers (towards the next frame of the job).
  TemporalGradients tg;
  if (const LayeredImage* next = held[1].get()) {
    auto g = temporal_gradients(layers, *next, settings_);
    if (!g.ok()) return g.status().with_context("frame " + std::to_string(frame) + ": ");
    tg = std::move(g.value());
  } else {
    const int w = direct->image.width(), h = direct->image.height();
    for (Image* im : {&tg.dt, &tg.dxdt, &tg.dydt, &tg.dt_var, &tg.dxdt_var, &tg.dydt_var}) *im = Image(w, h, 3);
    tg.failure_rate = Image(w, h, 1);
  }
  for (const char* name : {"primal", "dx", "dy"}) GDVR_RETURN_IF_ERROR(add_estimate(name));
  out.image.add("dt", {"R", "G", "B"}, std::move(tg.dt));
  out.image.add("dxdt", {"R", "G", "B"}, std::move(tg.dxdt));
  out.image.add("dydt", {"R", "G", "B"}, std::move(tg.dydt));
  out.image.layers.push_back(*direct);
  for (const char* name : {"primal_var", "dx_var", "dy_var"}) GDVR_RETURN_IF_ERROR(add_estimate(name));
  out.image.add("dt_var", {"R", "G", "B"}, std::move(tg.dt_var));
  out.image.add("dxdt_var", {"R", "G", "B"}, std::move(tg.dxdt_var));
  out.image.add("dydt_var", {"R", "G", "B"}, std::move(tg.dydt_var));
  if (const ImageLayer* l = layers.find("shift_failure_rate")) out.image.layers.push_back(*l);
  out.image.add("temporal_failure_rate", {"Y"}, std::move(tg.failure_rate));
  // Where the compensated constraints land (whole pixels; zero where dropped,
  // across a static pair and at the shot's end).
  if (settings_.compensates_motion())
    out.image.add("temporal_target", {"X", "Y"},
                  tg.target.empty() ? Image(direct->image.width(), direct->image.height(), 2) : std::move(tg.target));
  if (const ImageLayer* l = layers.find("motion")) out.image.layers.push_back(*l);
  else out.image.add("motion", {"X", "Y", "V"}, Image(direct->image.width(), direct->image.height(), 3));
  copy_feature_layers(layers, &out.image);
  if (settings_.window == 1)
    out.stats.left_out.push_back("temporal terms in the solve: window of 1 frame (spatial reconstruction)");
  if (!settings_.motion_vectors) out.stats.left_out.push_back("temporal masks: motion vectors off");
  else if (settings_.motion_compensation && !settings_.compensates_motion())
    out.stats.left_out.push_back(
        "motion compensation: not with temporal_shift reconnect (same-pixel dt; constraints whose surface moves "
        "more than a pixel per frame are dropped)");
  if (recon_stats.total_non_finite() > 0)
    out.stats.left_out.push_back(std::to_string(recon_stats.total_non_finite()) +
                                 " non-finite constraints dropped by the reconstruction");
  zero_non_finite_layers(&out);
  return out;
}

}  // namespace gdvr
