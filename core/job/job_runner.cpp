#include "core/job/job_runner.h"

#include <chrono>
#include <filesystem>
#include <set>

#include "core/gradient/gpt_integrator.h"
#include "core/recon/reconstruct.h"
#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"
#include "core/scene/scene_loader.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

bool path_is_inside(const fs::path& path, const fs::path& root) {
  auto p = fs::weakly_canonical(path), r = fs::weakly_canonical(root);
  auto mismatch = std::mismatch(r.begin(), r.end(), p.begin(), p.end());
  return mismatch.first == r.end();
}

// Everything a job needs before its first frame: the loaded scene with the
// job's overrides applied, the frame list, and what animates.
struct PreparedJob {
  Scene scene;
  std::vector<int> frames;
  Animation animation;  // the scene file's own animation, then the job's tracks
  std::vector<bool> animated_shapes;
  FrameRenderSettings render;
  bool gpt = false;
  GptSettings gpt_settings;
};

Expected<std::string> resolve_scene_path(const JobSpec& job, const JobRunOptions& options) {
  if (job.scene.empty()) return invalid_argument("job.scene: no scene given");
  fs::path p(job.scene);
  if (p.is_relative()) p = fs::path(!options.asset_root.empty() ? options.asset_root : options.base_dir) / p;
  if (!options.asset_root.empty() && !path_is_inside(p, options.asset_root))
    return invalid_argument("job.scene: '" + job.scene + "' lies outside the asset root");
  if (!fs::exists(p)) return not_found("job.scene: '" + job.scene + "' does not exist");
  if (!is_supported_scene_file(p.string()))
    return unimplemented("job.scene: '" + job.scene + "' is not a .xml, .gltf or .glb scene");
  return p.string();
}

Expected<PreparedJob> prepare_job(const JobSpec& job, const JobRunOptions& options) {
  if (job.integrator != "pt" && job.integrator != "gpt")
    return unimplemented("job.integrator: '" + job.integrator + "' is not available yet (supported: pt, gpt)");
  if (!(job.fps > 0) || !std::isfinite(job.fps)) return invalid_argument("job.fps must be a positive number");
  if (job.width < 0 || job.height < 0 || job.width > 16384 || job.height > 16384)
    return invalid_argument("job.width/job.height must be between 1 and 16384 (0 = the scene's)");
  if (job.spp < 0) return invalid_argument("job.spp must not be negative");
  if (job.time_budget_s < 0 || !std::isfinite(job.time_budget_s))
    return invalid_argument("job.time_budget_s must be a non-negative number");

  auto path = resolve_scene_path(job, options);
  if (!path.ok()) return path.status();
  LoadOptions load;
  load.params = job.params;
  load.asset_root = options.asset_root;
  auto loaded = load_scene(path.value(), load);
  if (!loaded.ok()) return loaded.status();

  PreparedJob prepared;
  prepared.scene = std::move(loaded->scene);
  // Tracks in the job file come after (and override) animation stored in the scene file.
  prepared.animation = std::move(loaded->animation);
  for (const Track& t : job.animation.tracks) prepared.animation.tracks.push_back(t);
  auto frames = parse_frame_range(job.frames);
  if (!frames.ok()) return frames.status().with_context("job.frames: ");
  prepared.frames = std::move(frames.value());
  GDVR_RETURN_IF_ERROR(validate_animation(prepared.animation, prepared.scene));

  prepared.animated_shapes.assign(prepared.scene.shapes.size(), false);
  for (const Track& track : prepared.animation.tracks)
    for (size_t i = 0; i < prepared.scene.shapes.size(); ++i)
      if (!track.target.empty() && prepared.scene.shapes[i].id == track.target) prepared.animated_shapes[i] = true;

  const RenderDefaults& d = prepared.scene.defaults;
  FrameRenderSettings& r = prepared.render;
  r.width = job.width > 0 ? job.width : d.width;
  r.height = job.height > 0 ? job.height : d.height;
  r.spp = job.spp > 0 ? job.spp : d.spp;
  r.time_budget_s = job.time_budget_s;
  if (r.time_budget_s > 0 && job.spp == 0) r.spp = 1;  // time budget: passes of 1 spp
  r.seed = job.seed;
  r.threads = options.threads;
  r.path.max_depth = d.max_depth;
  r.path.rr_depth = d.rr_depth;
  r.path.hide_emitters = d.hide_emitters;
  if (job.integrator == "gpt") {
    auto shift = parse_shift_mapping(job.shift);
    if (!shift.ok()) return shift.status().with_context("job.");
    auto method = parse_recon_method(job.reconstruction.method);
    if (!method.ok()) return method.status().with_context("job.reconstruction.");
    prepared.gpt = true;
    prepared.gpt_settings = GptSettings::defaults_for(shift.value());
    prepared.gpt_settings.recon.method = method.value();
    prepared.gpt_settings.recon.alpha = job.reconstruction.alpha;
    GDVR_RETURN_IF_ERROR(prepared.gpt_settings.validate().with_context("job: "));
  }
  return prepared;
}

}  // namespace

Status validate_job(const JobSpec& job, const JobRunOptions& options) { return prepare_job(job, options).status(); }

Status run_job(const JobSpec& job, const JobRunOptions& options, const JobCallbacks& callbacks,
               const std::atomic<bool>* cancel) {
  auto prepared = prepare_job(job, options);
  if (!prepared.ok()) return prepared.status();
  PreparedJob& pj = prepared.value();

  Scene frame_desc = pj.scene;
  if (!pj.animation.empty()) GDVR_RETURN_IF_ERROR(apply_animation(pj.animation, pj.frames.front() / job.fps, &frame_desc));
  auto frame_scene = FrameScene::create(frame_desc, pj.animated_shapes);
  if (!frame_scene.ok()) return frame_scene.status();
  FrameScene& scene = *frame_scene.value();

  const std::set<int> skip(options.skip_frames.begin(), options.skip_frames.end());
  std::vector<int> todo;
  for (int f : pj.frames)
    if (!skip.count(f)) todo.push_back(f);

  JobProgress progress;
  progress.frames_total = int(pj.frames.size());
  progress.frames_done = int(pj.frames.size() - todo.size());
  const auto job_start = std::chrono::steady_clock::now();
  int rendered_here = 0;
  auto report = [&](double frame_fraction) {
    if (!callbacks.on_progress) return;
    progress.fraction = (progress.frames_done + frame_fraction) / std::max(1, progress.frames_total);
    double spent = std::chrono::duration<double>(std::chrono::steady_clock::now() - job_start).count();
    double units_done = rendered_here + frame_fraction;
    int remaining = int(todo.size()) - rendered_here;
    progress.eta_seconds = units_done > 0.05 ? spent / units_done * (remaining - frame_fraction) : -1.0;
    callbacks.on_progress(progress);
  };

  for (int frame : todo) {
    if (cancel && cancel->load()) return cancelled("job cancelled");
    if (!pj.animation.empty()) {
      GDVR_RETURN_IF_ERROR(apply_animation(pj.animation, frame / job.fps, &frame_desc));
      GDVR_RETURN_IF_ERROR(scene.update(frame_desc));
    }
    FrameRenderControl control;
    control.cancel = cancel;
    control.on_progress = report;
    FrameOutput out;
    out.frame = frame;
    FrameStats& st = out.stats;
    st.frame = frame;
    if (pj.gpt) {
      auto result = render_frame_gpt(scene, pj.render, pj.gpt_settings, uint32_t(frame), control);
      if (!result.ok()) return result.status().with_context("frame " + std::to_string(frame) + ": ");
      GptFrameResult& r = result.value();
      GradientFilmBuffers& b = r.buffers;
      // Reconstruct the indirect part; light seen directly is added after the solve.
      GradientFrame gf;
      gf.buffer(Term::kPrimal) = b.primal;
      gf.buffer(Term::kDx) = b.dx;
      gf.buffer(Term::kDy) = b.dy;
      gf.variance(Term::kPrimal) = b.primal_var;
      gf.variance(Term::kDx) = b.dx_var;
      gf.variance(Term::kDy) = b.dy_var;
      auto recon = reconstruct_frame(gf, pj.gpt_settings.recon);
      if (!recon.ok()) return recon.status().with_context("frame " + std::to_string(frame) + ": reconstruction: ");
      Image final_image = std::move(recon->frames.front());
      for (size_t k = 0; k < final_image.data().size(); ++k) final_image.data()[k] += b.direct.data()[k];
      out.image.add("", {"R", "G", "B"}, std::move(final_image));
      out.image.add("primal", {"R", "G", "B"}, std::move(b.primal));
      out.image.add("dx", {"R", "G", "B"}, std::move(b.dx));
      out.image.add("dy", {"R", "G", "B"}, std::move(b.dy));
      out.image.add("direct", {"R", "G", "B"}, std::move(b.direct));
      out.image.add("shift_failure_rate", {"Y"}, std::move(b.shift_failure_rate));
      out.image.add("primal_var", {"R", "G", "B"}, std::move(b.primal_var));
      out.image.add("dx_var", {"R", "G", "B"}, std::move(b.dx_var));
      out.image.add("dy_var", {"R", "G", "B"}, std::move(b.dy_var));
      st.render_seconds = r.seconds;
      st.reconstruct_seconds = recon->stats.seconds;
      st.spp = r.spp;
      st.rays = r.rays;
      if (r.invalid_samples > 0)
        st.left_out.push_back(std::to_string(r.invalid_samples) + " non-finite samples or gradients dropped");
      if (recon->stats.total_non_finite() > 0)
        st.left_out.push_back(std::to_string(recon->stats.total_non_finite()) +
                              " non-finite constraints dropped by the reconstruction");
      bool glossy = false;
      for (const Bsdf& bsdf : scene.scene().bsdfs)
        glossy = glossy || bsdf.roughness() <= pj.gpt_settings.diffuse_roughness;
      if (!glossy && pj.gpt_settings.shift != ShiftMapping::kReplay)
        st.left_out.push_back("glossy shift machinery: no glossy or specular BSDF in the scene");
      st.left_out.push_back("temporal gradients: integrator gpt (spatial only)");
    } else {
      auto result = render_frame_pt(scene, pj.render, uint32_t(frame), control);
      if (!result.ok()) return result.status().with_context("frame " + std::to_string(frame) + ": ");
      FrameRenderResult& r = result.value();
      out.image.add("", {"R", "G", "B"}, std::move(r.color));
      out.image.add("direct", {"R", "G", "B"}, std::move(r.direct));
      out.image.add("variance", {"R", "G", "B"}, std::move(r.variance));
      st.render_seconds = r.seconds;
      st.spp = r.spp;
      st.rays = r.rays;
      if (r.invalid_samples > 0)
        st.left_out.push_back(std::to_string(r.invalid_samples) + " non-finite samples dropped");
      st.left_out.push_back("gradient sampling and reconstruction: integrator pt");
    }
    st.samples = uint64_t(st.spp) * uint64_t(pj.render.width) * uint64_t(pj.render.height);
    st.samples_per_second = st.render_seconds > 0 ? double(st.samples) / st.render_seconds : 0;
    st.rays_per_second = st.render_seconds > 0 ? double(st.rays) / st.render_seconds : 0;
    if (!scene.has_environment()) st.left_out.push_back("environment lookups: the scene has no environment");

    ++rendered_here;
    ++progress.frames_done;
    if (callbacks.on_frame_final) callbacks.on_frame_final(out);
    report(0.0);
  }
  return Status::Ok();
}

}  // namespace gdvr
