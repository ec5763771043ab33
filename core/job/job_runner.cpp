#include "core/job/job_runner.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <filesystem>
#include <set>

#include "core/io/layer_spill_file.h"
#include "core/job/frame_time_budget.h"
#include "core/job/integrators/integrator_runner.h"
#include "core/job/job_validation.h"
#include "core/render/feature_buffers.h"
#include "core/render/frame_scene.h"
#include "core/scene/scene_loader.h"
#include "core/temporal/denoised_data_term.h"
#include "core/temporal/stream_schedule.h"
#include "core/util/echo_text.h"
#include "core/util/path_confinement.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

// Everything a job needs before its first frame: the loaded scene with the
// job's overrides applied, the frame list, what animates, and its integrator.
struct PreparedJob {
  Scene scene;
  std::vector<int> frames;
  Animation animation;  // the scene file's own animation, then the job's tracks
  std::vector<bool> animated_shapes;
  FrameRenderSettings render;
  std::unique_ptr<IntegratorRunner> runner;
  // What the loader approximated or ignored, said with every frame's left_out.
  std::vector<std::string> scene_notes;
};

Expected<std::string> resolve_scene_path(const JobSpec& job, const JobRunOptions& options) {
  if (job.scene.empty()) return invalid_argument("job.scene: no scene given");
  const std::string shown = echo_text(job.scene);
  // A NUL would cut the path short in every C API below it.
  if (job.scene.find('\0') != std::string::npos) return invalid_argument("job.scene: '" + shown + "' contains a NUL byte");
  fs::path p(job.scene);
  if (p.is_relative()) p = fs::path(!options.asset_root.empty() ? options.asset_root : options.base_dir) / p;
  if (!options.asset_root.empty() && !is_inside_root(p, options.asset_root))
    return invalid_argument("job.scene: '" + shown + "' lies outside the asset root");
  // A file of another kind is the request's mistake (INVALID_ARGUMENT), not
  // a feature gdvr lacks.
  if (!is_supported_scene_file(job.scene))
    return invalid_argument("job.scene: '" + shown + "' is not a .xml, .gltf or .glb scene");
  std::error_code ec;
  if (!fs::exists(p, ec)) return not_found("job.scene: '" + shown + "' does not exist");
  return p.string();
}

Expected<PreparedJob> prepare_job(const JobSpec& job, const JobRunOptions& options) {
  GDVR_RETURN_IF_ERROR(validate(job));
  // What the job asks for that this process cannot give (not the request's mistake).
  if (job.reconstruction.data_term == DataTerm::kDenoised && !options.denoiser)
    return failed_precondition(
        "job.reconstruction.data_term: 'denoised' needs a denoiser, and this process has none (a build without "
        "Intel Open Image Denoise); use 'auto' or 'sampled'");
  auto path = resolve_scene_path(job, options);
  if (!path.ok()) return path.status();
  LoadOptions load;
  load.params = job.params;
  load.asset_root = options.asset_root;
  auto loaded = load_scene(path.value(), load);
  if (!loaded.ok()) return loaded.status();

  PreparedJob prepared;
  prepared.scene = std::move(loaded->scene);
  // A pixel filter replaced by box, 0.x settings without effect, repaired
  // meshes: a user comparing with Mitsuba needs to know. Paths are shown
  // relative to the scene's folder, so a service client never sees the
  // server's directories.
  const std::string scene_folder = fs::path(path.value()).parent_path().string() + "/";
  for (std::string w : prepared.scene.warnings) {
    for (size_t at; (at = w.find(scene_folder)) != std::string::npos;) w.erase(at, scene_folder.size());
    prepared.scene_notes.push_back("scene: " + w);
  }
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
  r.direct = default_direct_emission(is_gradient_domain(job.integrator));
  if (job.direct_light.strata) r.direct.strata = *job.direct_light.strata;
  if (job.direct_light.edge_strata) r.direct.edge_strata = *job.direct_light.edge_strata;
  r.direct.edge_strata = std::max(r.direct.edge_strata, r.direct.strata);
  GDVR_RETURN_IF_ERROR(r.direct.validate().with_context("job.direct_light: "));
  auto runner = make_integrator_runner(job, prepared.frames);
  if (!runner.ok()) return runner.status();
  prepared.runner = std::move(runner.value());
  return prepared;
}

// Stage 1 for one job: the prepared job and its world-space scene, moved to
// each frame's time before the integrator renders that frame.
class JobRenderer {
 public:
  static Expected<std::unique_ptr<JobRenderer>> create(const JobSpec& job, const JobRunOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    auto prepared = prepare_job(job, options);
    if (!prepared.ok()) return prepared.status();
    std::unique_ptr<JobRenderer> r(new JobRenderer(job, std::move(prepared.value()), start));
    // T-GPT's data term: denoised when asked for or, by default, when the
    // process has a denoiser (validate_job refused "denoised" without one).
    // Only the screened Poisson solves (L1, L2) weigh a data term by α; the
    // control variates combine the sampled primal with its variance.
    const ReconMethod method = job.reconstruction.method;
    const bool screened = method == ReconMethod::kL1 || method == ReconMethod::kL2;
    if (job.integrator == Integrator::kTgpt && screened && job.reconstruction.data_term != DataTerm::kSampled) {
      if (options.denoiser) {
        r->denoised_data_term_ = true;
        r->denoiser_ = options.denoiser;
      } else {
        r->pj_.scene_notes.push_back(
            "denoised data term: this process has no denoiser (a build without Intel Open Image Denoise); the "
            "window solve's data term is the sampled primal");
      }
    }
    Scene& desc = r->frame_desc_;
    desc = r->pj_.scene;
    if (!r->pj_.animation.empty())
      GDVR_RETURN_IF_ERROR(apply_animation(r->pj_.animation, r->pj_.frames.front() / job.fps, &desc));
    auto fs = FrameScene::create(desc, r->pj_.animated_shapes);
    if (!fs.ok()) return fs.status();
    r->scene_ = std::move(fs.value());
    return r;
  }

  const std::vector<int>& frames() const { return pj_.frames; }
  IntegratorRunner& runner() { return *pj_.runner; }

  // The job's time budget over `frames` frames (none without time_budget_s).
  // `caller_prior_s`: what the caller is expected to spend per final frame
  // until one is measured; `includes_finalize` false: this process only
  // renders (a farm task), so stage 2 and the output are not its cost.
  void start_budget(int frames, double caller_prior_s, bool includes_finalize) {
    if (job_.time_budget_s <= 0) return;
    if (!includes_finalize) {
      budget_ = std::make_unique<FrameTimeBudget>(FrameTimeBudget::stage1_only(job_.time_budget_s, frames));
      return;
    }
    const double stage2 = pj_.runner->finalize_seconds_prior(pj_.render, int(pj_.frames.size()));
    budget_ = std::make_unique<FrameTimeBudget>(job_.time_budget_s, frames, stage2, caller_prior_s);
  }
  FrameTimeBudget* budget() { return budget_.get(); }
  // Seconds since the job began (scene loading included: the user waits for it).
  double clock() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

  Expected<FrameBuffers> render(int frame, const FrameRenderControl& control) {
    const double frame_start = clock();
    if (budget_) budget_->begin_frame(frame_start);
    if (!pj_.animation.empty()) {
      GDVR_RETURN_IF_ERROR(apply_animation(pj_.animation, frame / job_.fps, &frame_desc_));
      GDVR_RETURN_IF_ERROR(scene_->update(frame_desc_));
    }
    FrameBuffers out;
    out.frame = frame;
    FrameStats& st = out.stats;
    st.frame = frame;
    // The feature pass first: a fixed cost the budget then takes off the
    // frame before the integrator's allowance is set.
    LayeredImage features;
    GDVR_RETURN_IF_ERROR(render_features(control, &features, &st));
    if (budget_) budget_->plan_frame(clock());
    // Another frame's description: this frame's with the animation at that time.
    auto describe_frame = [this](int other, Scene* desc) -> Status {
      *desc = frame_desc_;
      if (!pj_.animation.empty()) GDVR_RETURN_IF_ERROR(apply_animation(pj_.animation, other / job_.fps, desc));
      return Status::Ok();
    };
    const FrameRenderContext context{*scene_, frame_desc_, pj_.render, pj_.animated_shapes,
                                     describe_frame, control, budget_.get()};
    GDVR_RETURN_IF_ERROR(pj_.runner->render(context, frame, &out));
    for (ImageLayer& l : features.layers) out.layers.layers.push_back(std::move(l));
    if (denoised_data_term_)
      GDVR_RETURN_IF_ERROR(add_denoised_data_term(denoiser_, &out.layers).with_context("frame " + std::to_string(frame) + ": "));
    if (budget_) pj_.runner->calibrate_stage2(out.layers, budget_.get());
    st.samples = uint64_t(st.spp) * uint64_t(pj_.render.width) * uint64_t(pj_.render.height);
    st.samples_per_second = st.render_seconds > 0 ? double(st.samples) / st.render_seconds : 0;
    st.rays_per_second = st.render_seconds > 0 ? double(st.rays) / st.render_seconds : 0;
    if (!scene_->has_environment()) st.left_out.push_back("environment lookups: the scene has no environment");
    st.left_out.insert(st.left_out.end(), pj_.scene_notes.begin(), pj_.scene_notes.end());
    const double frame_end = clock();
    st.stage1_seconds = frame_end - frame_start;
    if (budget_) budget_->end_frame(frame_end);
    return out;
  }

 private:
  JobRenderer(const JobSpec& job, PreparedJob pj, std::chrono::steady_clock::time_point start)
      : job_(job), pj_(std::move(pj)), start_(start) {}

  // The frame's feature buffers (albedo, N, Z) into `layers`, unless the
  // job's EXR layer selection leaves them all out.
  Status render_features(const FrameRenderControl& control, LayeredImage* layers, FrameStats* stats) {
    const std::vector<std::string>& selected = job_.outputs.exr_layers;
    const bool wanted = selected.empty() || std::any_of(selected.begin(), selected.end(), [](const std::string& l) {
                          const auto& names = feature_layer_names();
                          return std::find(names.begin(), names.end(), l) != names.end();
                        });
    if (!wanted && !denoised_data_term_) return Status::Ok();  // the denoiser's guides
    auto features =
        render_feature_buffers(*scene_, pj_.render, feature_buffer_settings_for(pj_.render.spp), control.cancel);
    if (!features.ok()) return features.status();
    stats->feature_seconds = features->seconds;
    add_feature_layers(std::move(features.value()), layers);
    return Status::Ok();
  }

  const JobSpec& job_;
  PreparedJob pj_;
  bool denoised_data_term_ = false;
  FrameDenoiser denoiser_;
  std::chrono::steady_clock::time_point start_;
  Scene frame_desc_;
  std::unique_ptr<FrameScene> scene_;
  std::unique_ptr<FrameTimeBudget> budget_;
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

namespace {

// "the job's width", or where in the scene the value was set and which
// <default> parameter (overridden by the job's params or not) fed it.
std::string origin_of(bool from_job, const char* job_field, const SettingOrigin& origin, const JobSpec& job,
                      const char* builtin) {
  if (from_job) return std::string("the job's ") + job_field;
  for (const std::string& p : origin.params) {
    if (job.params.count(p)) return "params." + echo_text(p) + " (used by the scene at " + origin.where + ")";
  }
  if (!origin.params.empty())
    return "the scene's <default name=\"" + origin.params.front() + "\"> (used at " + origin.where + ")";
  if (!origin.where.empty()) return "the scene (" + origin.where + ")";
  return std::string("gdvr's default for a scene without ") + builtin;
}

}  // namespace

Expected<ResolvedRender> resolve_job(const JobSpec& job, const JobRunOptions& options) {
  auto prepared = prepare_job(job, options);
  if (!prepared.ok()) return prepared.status();
  const PreparedJob& pj = prepared.value();
  const RenderDefaults& d = pj.scene.defaults;
  ResolvedRender out;
  out.width = {pj.render.width, origin_of(job.width > 0, "width", d.width_origin, job, "a film")};
  out.height = {pj.render.height, origin_of(job.height > 0, "height", d.height_origin, job, "a film")};
  if (job.spp > 0) out.spp = {pj.render.spp, "the job's spp"};
  else if (job.time_budget_s > 0) out.spp = {pj.render.spp, "1-spp passes of the job's time_budget_s"};
  else out.spp = {pj.render.spp, origin_of(false, "spp", d.spp_origin, job, "a sampler")};
  out.time_budget_s = pj.render.time_budget_s;
  out.frames = int(pj.frames.size());
  return out;
}

std::vector<int> frames_needed_to_finalize(const JobSpec& job, const std::vector<int>& job_frames, int frame) {
  auto runner = make_integrator_runner(job, job_frames);
  // A job whose settings do not hold fails at finalize; until then it needs its own frame.
  return runner.ok() ? runner.value()->frames_needed(frame) : std::vector<int>{frame};
}

Expected<FrameOutput> finalize_frame(const JobSpec& job, int frame, const std::map<int, FrameBuffers>& buffers) {
  auto finalizer = JobFinalizer::create(job);
  if (!finalizer.ok()) return finalizer.status();
  return finalizer.value()->finalize(frame, buffers);
}

Expected<std::unique_ptr<JobFinalizer>> JobFinalizer::create(const JobSpec& job) {
  auto frames = parse_frame_range(job.frames);
  if (!frames.ok()) return frames.status().with_context("job.frames: ");
  auto runner = make_integrator_runner(job, std::move(frames.value()));
  if (!runner.ok()) return runner.status();
  return std::unique_ptr<JobFinalizer>(new JobFinalizer(std::move(runner.value())));
}

JobFinalizer::JobFinalizer(std::unique_ptr<IntegratorRunner> runner) : runner_(std::move(runner)) {}
JobFinalizer::~JobFinalizer() = default;

std::vector<int> JobFinalizer::frames_needed(int frame) const { return runner_->frames_needed(frame); }

Expected<FrameOutput> JobFinalizer::finalize(int frame, const std::map<int, FrameBuffers>& buffers) {
  return runner_->finalize(frame, buffers);
}

int JobFinalizer::windows_solved() const { return runner_->windows_solved(); }

Expected<TileGrid> JobFinalizer::tile_grid(int width, int height) const { return runner_->tile_grid(width, height); }

Expected<Image> JobFinalizer::reconstruct_tiles(int frame, const std::vector<int>& tiles,
                                                const std::map<int, FrameBuffers>& buffers) {
  return runner_->reconstruct_tiles(frame, tiles, buffers);
}

Expected<FrameOutput> JobFinalizer::finalize_solved(int frame, const std::map<int, FrameBuffers>& buffers, Image solved) {
  return runner_->finalize_solved(frame, buffers, std::move(solved));
}

Status render_job_buffers(const JobSpec& job, const JobRunOptions& options, const std::vector<int>& frames,
                          const std::function<Status(FrameBuffers&&)>& on_buffers,
                          const std::function<void(const JobProgress&)>& on_progress,
                          const std::atomic<bool>* cancel) {
  auto renderer = JobRenderer::create(job, options);
  if (!renderer.ok()) return renderer.status();
  const std::vector<int>& job_frames = renderer.value()->frames();
  const std::set<int> valid(job_frames.begin(), job_frames.end());
  for (int f : frames)
    if (!valid.count(f)) return invalid_argument("frame " + std::to_string(f) + " is not in the job's frame range");
  ProgressTracker progress(int(frames.size()), 0, int(frames.size()), on_progress);
  // A farm task renders only: its budget is stage 1's (the finalize task runs elsewhere).
  renderer.value()->start_budget(int(frames.size()), 0, /* includes_finalize = */ false);
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
  const std::vector<int>& job_frames = renderer.value()->frames();
  IntegratorRunner& runner = renderer.value()->runner();

  const std::set<int> skip(options.skip_frames.begin(), options.skip_frames.end());
  std::vector<int> todo;  // frames to finalize, in order
  for (int f : job_frames)
    if (!skip.count(f)) todo.push_back(f);
  // Frames to render: everything a frame still to finalize reads (for tgpt its
  // windows, which may include already final frames after a resume).
  std::vector<std::vector<int>> needs;
  for (int f : todo) needs.push_back(runner.frames_needed(f));
  StreamSchedule schedule(todo, std::move(needs));
  // Progress counts rendered frames (the cost); for pt and gpt that is the
  // frames finalized, for tgpt the final frames trail by up to a window.
  const int render_count = int(schedule.render_order().size());
  const int already_done = int(job_frames.size() - todo.size());
  ProgressTracker progress(already_done + render_count, already_done, render_count, callbacks.on_progress);

  // A time budget pays for everything from here to the last final frame.
  renderer.value()->start_budget(render_count, options.caller_seconds_per_frame, /* includes_finalize = */ true);
  FrameTimeBudget* budget = renderer.value()->budget();
  bool caller_probed = false;
  // Streaming: after each rendered frame, finalize (in order) every frame whose
  // buffers are all in, then drop the buffers no later frame reads; what is
  // held is bounded by the reconstruction window (1 frame for pt and gpt).
  std::map<int, FrameBuffers> buffers;
  for (int frame : schedule.render_order()) {
    if (cancel && cancel->load()) return cancelled("job cancelled");
    FrameRenderControl control;
    control.cancel = cancel;
    control.on_progress = [&](double f) { progress.frame_progress(f); };
    auto rendered = renderer.value()->render(frame, control);
    if (!rendered.ok()) return rendered.status().with_context("frame " + std::to_string(frame) + ": ");
    buffers[frame] = std::move(rendered.value());
    if (options.memory_limit_bytes >= 0 && runner.reads_spilled_buffers()) {
      // Over the limit, the frame just rendered goes to disk (finalize and
      // the tiled window solve read it back a region at a time).
      long long held = 0;
      for (const auto& [f, fb] : buffers) held += layer_pixel_bytes(fb.layers);
      if (held > options.memory_limit_bytes) {
        FrameBuffers& fb = buffers[frame];
        auto file = LayerSpillFile::spill(options.spill_dir, fb.layers);
        if (!file.ok()) return file.status().with_context("frame " + std::to_string(frame) + ": --memory-limit: ");
        fb.on_disk = std::move(file.value());
        fb.layers = LayeredImage();
      }
    }
    schedule.rendered(frame);
    progress.frame_done();
    // Stage 2 and the caller's work on each final frame: on the budget too.
    const double finalize_start = renderer.value()->clock();
    int finalized = 0;
    for (int f = schedule.ready(); f >= 0; f = schedule.ready()) {
      auto out = runner.finalize(f, buffers);
      if (!out.ok()) return out.status();
      if (callbacks.on_frame_final) callbacks.on_frame_final(out.value());
      schedule.finalized();
      ++finalized;
    }
    if (budget) budget->record_finalize(finalized, renderer.value()->clock() - finalize_start);
    // A frame that cannot come out yet (T-GPT waits for its window): the
    // caller's work per final frame is unknown until the first does, so it
    // estimates it on these buffers, once.
    if (budget && !caller_probed && finalized == 0 && callbacks.estimate_frame_final_seconds) {
      caller_probed = true;
      budget->set_caller_prior(callbacks.estimate_frame_final_seconds(buffers.at(frame)));
    }
    const int next_out = schedule.done() ? INT_MAX : todo[size_t(schedule.next_index())];
    for (int f : schedule.releasable([&](int held) { return runner.buffers_needed(held, next_out); }))
      buffers.erase(f);
  }
  return Status::Ok();
}

}  // namespace gdvr
