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

// Stage 1 state for one job: the prepared job and its world-space scene,
// moved to each frame's time before that frame renders.
class JobRenderer {
 public:
  static Expected<std::unique_ptr<JobRenderer>> create(const JobSpec& job, const JobRunOptions& options) {
    auto prepared = prepare_job(job, options);
    if (!prepared.ok()) return prepared.status();
    std::unique_ptr<JobRenderer> r(new JobRenderer(job, std::move(prepared.value())));
    Scene& desc = r->frame_desc_;
    desc = r->pj_.scene;
    if (!r->pj_.animation.empty())
      GDVR_RETURN_IF_ERROR(apply_animation(r->pj_.animation, r->pj_.frames.front() / job.fps, &desc));
    auto fs = FrameScene::create(desc, r->pj_.animated_shapes);
    if (!fs.ok()) return fs.status();
    r->scene_ = std::move(fs.value());
    return r;
  }

  const PreparedJob& prepared() const { return pj_; }

  Expected<FrameBuffers> render(int frame, const FrameRenderControl& control) {
    if (!pj_.animation.empty()) {
      GDVR_RETURN_IF_ERROR(apply_animation(pj_.animation, frame / job_.fps, &frame_desc_));
      GDVR_RETURN_IF_ERROR(scene_->update(frame_desc_));
    }
    FrameBuffers out;
    out.frame = frame;
    FrameStats& st = out.stats;
    st.frame = frame;
    if (pj_.gpt) {
      auto result = render_frame_gpt(*scene_, pj_.render, pj_.gpt_settings, uint32_t(frame), control);
      if (!result.ok()) return result.status();
      GptFrameResult& r = result.value();
      GradientFilmBuffers& b = r.buffers;
      out.layers.add("primal", {"R", "G", "B"}, std::move(b.primal));
      out.layers.add("dx", {"R", "G", "B"}, std::move(b.dx));
      out.layers.add("dy", {"R", "G", "B"}, std::move(b.dy));
      out.layers.add("direct", {"R", "G", "B"}, std::move(b.direct));
      out.layers.add("shift_failure_rate", {"Y"}, std::move(b.shift_failure_rate));
      out.layers.add("primal_var", {"R", "G", "B"}, std::move(b.primal_var));
      out.layers.add("dx_var", {"R", "G", "B"}, std::move(b.dx_var));
      out.layers.add("dy_var", {"R", "G", "B"}, std::move(b.dy_var));
      st.render_seconds = r.seconds;
      st.spp = r.spp;
      st.rays = r.rays;
      if (r.invalid_samples > 0)
        st.left_out.push_back(std::to_string(r.invalid_samples) + " non-finite samples or gradients dropped");
      bool glossy = false;
      for (const Bsdf& bsdf : scene_->scene().bsdfs)
        glossy = glossy || bsdf.roughness() <= pj_.gpt_settings.diffuse_roughness;
      if (!glossy && pj_.gpt_settings.shift != ShiftMapping::kReplay)
        st.left_out.push_back("glossy shift machinery: no glossy or specular BSDF in the scene");
      st.left_out.push_back("temporal gradients: integrator gpt (spatial only)");
    } else {
      auto result = render_frame_pt(*scene_, pj_.render, uint32_t(frame), control);
      if (!result.ok()) return result.status();
      FrameRenderResult& r = result.value();
      out.layers.add("", {"R", "G", "B"}, std::move(r.color));
      out.layers.add("direct", {"R", "G", "B"}, std::move(r.direct));
      out.layers.add("variance", {"R", "G", "B"}, std::move(r.variance));
      st.render_seconds = r.seconds;
      st.spp = r.spp;
      st.rays = r.rays;
      if (r.invalid_samples > 0) st.left_out.push_back(std::to_string(r.invalid_samples) + " non-finite samples dropped");
      st.left_out.push_back("gradient sampling and reconstruction: integrator pt");
    }
    st.samples = uint64_t(st.spp) * uint64_t(pj_.render.width) * uint64_t(pj_.render.height);
    st.samples_per_second = st.render_seconds > 0 ? double(st.samples) / st.render_seconds : 0;
    st.rays_per_second = st.render_seconds > 0 ? double(st.rays) / st.render_seconds : 0;
    if (!scene_->has_environment()) st.left_out.push_back("environment lookups: the scene has no environment");
    return out;
  }

 private:
  JobRenderer(const JobSpec& job, PreparedJob pj) : job_(job), pj_(std::move(pj)) {}
  const JobSpec& job_;
  PreparedJob pj_;
  Scene frame_desc_;
  std::unique_ptr<FrameScene> scene_;
};

// Progress over a list of frames: fraction of the whole job and an ETA from the
// average time of the frames rendered in this run.
class ProgressTracker {
 public:
  ProgressTracker(int total, int already_done, int todo, std::function<void(const JobProgress&)> sink)
      : todo_(todo), sink_(std::move(sink)), start_(std::chrono::steady_clock::now()) {
    progress_.frames_total = total;
    progress_.frames_done = already_done;
  }
  void frame_progress(double frame_fraction) {
    if (!sink_) return;
    progress_.fraction = (progress_.frames_done + frame_fraction) / std::max(1, progress_.frames_total);
    double spent = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    double units_done = rendered_here_ + frame_fraction;
    progress_.eta_seconds = units_done > 0.05 ? spent / units_done * (todo_ - rendered_here_ - frame_fraction) : -1.0;
    sink_(progress_);
  }
  void frame_done() {
    ++rendered_here_;
    ++progress_.frames_done;
    frame_progress(0.0);
  }

 private:
  int todo_, rendered_here_ = 0;
  JobProgress progress_;
  std::function<void(const JobProgress&)> sink_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace

Status validate_job(const JobSpec& job, const JobRunOptions& options) { return prepare_job(job, options).status(); }

std::vector<int> frames_needed_to_finalize(const JobSpec&, const std::vector<int>&, int frame) {
  // pt and gpt finalize each frame from its own buffers.
  return {frame};
}

Expected<FrameOutput> finalize_frame(const JobSpec& job, int frame, const std::map<int, FrameBuffers>& buffers) {
  auto it = buffers.find(frame);
  if (it == buffers.end()) return failed_precondition("finalize: no buffers for frame " + std::to_string(frame));
  const FrameBuffers& fb = it->second;
  FrameOutput out;
  out.frame = frame;
  out.stats = fb.stats;
  if (job.integrator == "pt") {
    out.image = fb.layers;
    return out;
  }
  // Gradient-domain: reconstruct the indirect part; light seen directly from
  // the camera is kept out of the solve and added after it (REFERENCE.md §1).
  auto method = parse_recon_method(job.reconstruction.method);
  if (!method.ok()) return method.status().with_context("job.reconstruction.");
  ReconSettings recon = GptSettings::defaults_for(ShiftMapping::kReconnect).recon;
  recon.method = method.value();
  recon.alpha = job.reconstruction.alpha;
  auto layer = [&](const char* name) -> const Image* {
    const ImageLayer* l = fb.layers.find(name);
    return l ? &l->image : nullptr;
  };
  for (const char* name : {"primal", "dx", "dy", "direct", "primal_var", "dx_var", "dy_var"})
    if (!layer(name)) return invalid_argument(std::string("finalize: frame buffers lack the '") + name + "' layer");
  GradientFrame gf;
  gf.buffer(Term::kPrimal) = *layer("primal");
  gf.buffer(Term::kDx) = *layer("dx");
  gf.buffer(Term::kDy) = *layer("dy");
  gf.variance(Term::kPrimal) = *layer("primal_var");
  gf.variance(Term::kDx) = *layer("dx_var");
  gf.variance(Term::kDy) = *layer("dy_var");
  auto solved = reconstruct_frame(gf, recon);
  if (!solved.ok()) return solved.status().with_context("frame " + std::to_string(frame) + ": reconstruction: ");
  Image final_image = std::move(solved->frames.front());
  const Image& direct = *layer("direct");
  for (size_t k = 0; k < final_image.data().size(); ++k) final_image.data()[k] += direct.data()[k];
  out.image.add("", {"R", "G", "B"}, std::move(final_image));
  for (const ImageLayer& l : fb.layers.layers) out.image.layers.push_back(l);
  out.stats.reconstruct_seconds = solved->stats.seconds;
  if (solved->stats.total_non_finite() > 0)
    out.stats.left_out.push_back(std::to_string(solved->stats.total_non_finite()) +
                                 " non-finite constraints dropped by the reconstruction");
  return out;
}

Status render_job_buffers(const JobSpec& job, const JobRunOptions& options, const std::vector<int>& frames,
                          const std::function<Status(FrameBuffers&&)>& on_buffers,
                          const std::function<void(const JobProgress&)>& on_progress,
                          const std::atomic<bool>* cancel) {
  auto renderer = JobRenderer::create(job, options);
  if (!renderer.ok()) return renderer.status();
  const std::vector<int>& job_frames = renderer.value()->prepared().frames;
  const std::set<int> valid(job_frames.begin(), job_frames.end());
  for (int f : frames)
    if (!valid.count(f)) return invalid_argument("frame " + std::to_string(f) + " is not in the job's frame range");
  ProgressTracker progress(int(frames.size()), 0, int(frames.size()), on_progress);
  for (int frame : frames) {
    if (cancel && cancel->load()) return cancelled("job cancelled");
    FrameRenderControl control;
    control.cancel = cancel;
    control.on_progress = [&](double f) { progress.frame_progress(f); };
    auto buffers = renderer.value()->render(frame, control);
    if (!buffers.ok()) return buffers.status().with_context("frame " + std::to_string(frame) + ": ");
    GDVR_RETURN_IF_ERROR(on_buffers(std::move(buffers.value())));
    progress.frame_done();
  }
  return Status::Ok();
}

Status run_job(const JobSpec& job, const JobRunOptions& options, const JobCallbacks& callbacks,
               const std::atomic<bool>* cancel) {
  auto renderer = JobRenderer::create(job, options);
  if (!renderer.ok()) return renderer.status();
  const std::vector<int>& job_frames = renderer.value()->prepared().frames;

  const std::set<int> skip(options.skip_frames.begin(), options.skip_frames.end());
  std::vector<int> todo;
  for (int f : job_frames)
    if (!skip.count(f)) todo.push_back(f);
  ProgressTracker progress(int(job_frames.size()), int(job_frames.size() - todo.size()), int(todo.size()),
                           callbacks.on_progress);

  // Buffers stay in memory only while a frame that still has to be finalized needs them.
  std::map<int, FrameBuffers> buffers;
  for (int frame : todo) {
    if (cancel && cancel->load()) return cancelled("job cancelled");
    FrameRenderControl control;
    control.cancel = cancel;
    control.on_progress = [&](double f) { progress.frame_progress(f); };
    auto rendered = renderer.value()->render(frame, control);
    if (!rendered.ok()) return rendered.status().with_context("frame " + std::to_string(frame) + ": ");
    buffers[frame] = std::move(rendered.value());
    auto out = finalize_frame(job, frame, buffers);
    if (!out.ok()) return out.status();
    buffers.erase(frame);
    if (callbacks.on_frame_final) callbacks.on_frame_final(out.value());
    progress.frame_done();
  }
  return Status::Ok();
}

}  // namespace gdvr
