#include "core/job/job_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>

#include "core/gradient/gpt_integrator.h"
#include "core/recon/reconstruct.h"
#include "core/render/feature_buffers.h"
#include "core/render/vector_batch.h"
#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"
#include "core/scene/scene_loader.h"
#include "core/temporal/pass_schedule.h"
#include "core/temporal/stream_schedule.h"
#include "core/temporal/temporal_buffers.h"
#include "core/temporal/temporal_window.h"
#include "core/temporal/tgpt_frame.h"
#include "core/util/echo_text.h"
#include "core/util/path_confinement.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

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
  bool tgpt = false;
  TgptSettings tgpt_settings;
  // What the loader approximated or ignored, said with every frame's left_out.
  std::vector<std::string> scene_notes;
};

// The job's per-term weights (primal, dx, dy, dt, dxdt, dydt), when given.
void apply_term_weights(const ReconstructionSpec& spec, ReconSettings* recon) {
  if (spec.term_weights.size() != size_t(kTermCount)) return;
  for (int t = 0; t < kTermCount; ++t) recon->term_weights[size_t(t)] = spec.term_weights[size_t(t)];
}

// T-GPT options from the job (stage 1 and stage 2 both build them, so a farm's
// finalize process needs only the job and the buffers).
Expected<TgptSettings> tgpt_settings_for(const JobSpec& job) {
  auto shift = parse_shift_mapping(job.shift);
  if (!shift.ok()) return shift.status().with_context("job.");
  auto method = parse_recon_method(job.reconstruction.method);
  if (!method.ok()) return method.status().with_context("job.reconstruction.");
  auto temporal_shift = parse_temporal_shift(job.temporal_shift);
  if (!temporal_shift.ok()) return temporal_shift.status().with_context("job.");
  TgptSettings s;
  s.gpt = TgptSettings::gpt_defaults_for(shift.value());
  s.temporal_shift = temporal_shift.value();
  s.recon.method = method.value();
  s.recon.alpha = job.reconstruction.alpha;
  apply_term_weights(job.reconstruction, &s.recon);
  s.window = job.reconstruction.window;
  if (s.window < 1)
    return invalid_argument("job.reconstruction.window must be at least 1 (got " + std::to_string(s.window) + ")");
  GDVR_RETURN_IF_ERROR(s.validate().with_context("job: "));
  return s;
}

int frame_position(const std::vector<int>& frames, int frame) {
  auto it = std::lower_bound(frames.begin(), frames.end(), frame);
  return it != frames.end() && *it == frame ? int(it - frames.begin()) : -1;
}

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
  if (job.integrator != "pt" && job.integrator != "gpt" && job.integrator != "tgpt")
    return invalid_argument("job.integrator: '" + echo_text(job.integrator) + "' is not available (supported: pt, gpt, tgpt)");
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
  r.direct = default_direct_emission(/*gradient_domain=*/job.integrator != "pt");
  if (job.direct_light.strata >= 0) r.direct.strata = job.direct_light.strata;
  if (job.direct_light.edge_strata >= 0) r.direct.edge_strata = job.direct_light.edge_strata;
  r.direct.edge_strata = std::max(r.direct.edge_strata, r.direct.strata);
  GDVR_RETURN_IF_ERROR(r.direct.validate().with_context("job.direct_light: "));
  if (job.integrator == "gpt") {
    auto shift = parse_shift_mapping(job.shift);
    if (!shift.ok()) return shift.status().with_context("job.");
    auto method = parse_recon_method(job.reconstruction.method);
    if (!method.ok()) return method.status().with_context("job.reconstruction.");
    prepared.gpt = true;
    prepared.gpt_settings = GptSettings::defaults_for(shift.value());
    prepared.gpt_settings.recon.method = method.value();
    prepared.gpt_settings.recon.alpha = job.reconstruction.alpha;
    apply_term_weights(job.reconstruction, &prepared.gpt_settings.recon);
    GDVR_RETURN_IF_ERROR(prepared.gpt_settings.validate().with_context("job: "));
  }
  if (job.integrator == "tgpt") {
    auto s = tgpt_settings_for(job);
    if (!s.ok()) return s.status();
    prepared.tgpt = true;
    prepared.tgpt_settings = std::move(s.value());
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
    if (pj_.tgpt) {
      GDVR_RETURN_IF_ERROR(render_tgpt(frame, control, &out));
    } else if (pj_.gpt) {
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
      const std::string scalar_why = why_no_vector_batch(*scene_, pj_.render.path, pj_.render.paths_in_flight);
      if (!scalar_why.empty()) st.left_out.push_back("the vector path batch's AVX2/AVX-512 kernel: " + scalar_why);
    }
    GDVR_RETURN_IF_ERROR(render_features(control, &out));
    st.samples = uint64_t(st.spp) * uint64_t(pj_.render.width) * uint64_t(pj_.render.height);
    st.samples_per_second = st.render_seconds > 0 ? double(st.samples) / st.render_seconds : 0;
    st.rays_per_second = st.render_seconds > 0 ? double(st.rays) / st.render_seconds : 0;
    if (!scene_->has_environment()) st.left_out.push_back("environment lookups: the scene has no environment");
    st.left_out.insert(st.left_out.end(), pj_.scene_notes.begin(), pj_.scene_notes.end());
    return out;
  }

 private:
  JobRenderer(const JobSpec& job, PreparedJob pj) : job_(job), pj_(std::move(pj)) {}

  // The frame's feature buffers (albedo, N, Z) beside the integrator's
  // layers, unless the job's EXR layer selection leaves them all out.
  Status render_features(const FrameRenderControl& control, FrameBuffers* out) {
    const std::vector<std::string>& selected = job_.outputs.exr_layers;
    const bool wanted = selected.empty() || std::any_of(selected.begin(), selected.end(), [](const std::string& l) {
                          const auto& names = feature_layer_names();
                          return std::find(names.begin(), names.end(), l) != names.end();
                        });
    if (!wanted) return Status::Ok();
    auto features =
        render_feature_buffers(*scene_, pj_.render, feature_buffer_settings_for(pj_.render.spp), control.cancel);
    if (!features.ok()) return features.status();
    out->stats.feature_seconds = features->seconds;
    add_feature_layers(std::move(features.value()), &out->layers);
    return Status::Ok();
  }

  // ---- T-GPT stage 1: two half passes, motion fields where the pair changes ----
  Status render_tgpt(int frame, const FrameRenderControl& control, FrameBuffers* out) {
    const std::vector<int>& frames = pj_.frames;
    const int pos = frame_position(frames, frame);
    if (pos < 0) return invalid_argument("frame " + std::to_string(frame) + " is not in the job's frame range");
    // The neighbours' animated descriptions (copies share meshes and textures).
    Scene prev_desc, next_desc;
    TgptNeighbourhood nb;
    nb.at_t = &frame_desc_;
    auto neighbour = [&](int f, Scene* desc) -> Status {
      *desc = frame_desc_;
      if (!pj_.animation.empty()) GDVR_RETURN_IF_ERROR(apply_animation(pj_.animation, f / job_.fps, desc));
      return Status::Ok();
    };
    if (pos > 0) {
      GDVR_RETURN_IF_ERROR(neighbour(frames[size_t(pos) - 1], &prev_desc));
      nb.prev = &prev_desc;
      nb.to_prev = detect_changes(prev_desc, frame_desc_);
    }
    if (size_t(pos) + 1 < frames.size()) {
      GDVR_RETURN_IF_ERROR(neighbour(frames[size_t(pos) + 1], &next_desc));
      nb.next = &next_desc;
      nb.to_next = detect_changes(frame_desc_, next_desc);
    }
    // The path-space temporal shift traces in the neighbours' scenes: keep one
    // FrameScene per side, moved to the neighbour's time (built once).
    if (pj_.tgpt_settings.temporal_shift == TemporalShiftMapping::kReconnect) {
      auto scene_at = [&](const Scene& desc, std::unique_ptr<FrameScene>* slot) -> Status {
        if (*slot) return (*slot)->update(desc);
        auto fs = FrameScene::create(desc, pj_.animated_shapes);
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
    // Across a static pair, pass A of t replays pass B of t−1 in an identical
    // scene: same numbers, same image; copy it when we rendered it (and no
    // time budget made the pass sizes differ).
    const GradientFilmBuffers* reuse = nullptr;
    if (pos > 0 && last_b_frame_ == frames[size_t(pos) - 1] && !nb.to_prev.any() && pj_.render.time_budget_s <= 0)
      reuse = &last_b_;
    auto result = render_tgpt_frame(*scene_, pj_.render, pj_.tgpt_settings, tgpt_pass_streams(frames, size_t(pos)),
                                    nb, reuse, control);
    if (!result.ok()) return result.status();
    TgptFrameRender& r = result.value();
    last_b_frame_ = std::numeric_limits<int>::min();
    if (nb.next && !nb.to_next.any()) {
      last_b_ = r.b;
      last_b_frame_ = frame;
    }
    FrameStats& st = out->stats;
    st.render_seconds = r.seconds;
    st.spp = r.spp;
    st.rays = r.rays;
    st.temporal_rays = r.temporal_rays;
    if (r.invalid_samples > 0)
      st.left_out.push_back(std::to_string(r.invalid_samples) + " non-finite samples or gradients dropped");
    bool glossy = false;
    for (const Bsdf& bsdf : scene_->scene().bsdfs)
      glossy = glossy || bsdf.roughness() <= pj_.tgpt_settings.gpt.diffuse_roughness;
    if (!glossy && pj_.tgpt_settings.gpt.shift != ShiftMapping::kReplay)
      st.left_out.push_back("glossy shift machinery: no glossy or specular BSDF in the scene");
    for (std::string& s : r.left_out) st.left_out.push_back(std::move(s));
    out->layers = tgpt_frame_layers(std::move(r));
    return Status::Ok();
  }

  const JobSpec& job_;
  PreparedJob pj_;
  Scene frame_desc_;
  std::unique_ptr<FrameScene> scene_;
  std::unique_ptr<FrameScene> scene_prev_, scene_next_;  // tgpt with temporal_shift reconnect
  GradientFilmBuffers last_b_;  // pass B of frame last_b_frame_, kept only across a static pair
  int last_b_frame_ = std::numeric_limits<int>::min();
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
  const int pos = frame_position(job_frames, frame);
  if (job.integrator != "tgpt" || pos < 0) return {frame};  // pt and gpt: the frame's own buffers
  // tgpt: every frame of every window containing the frame, and the next frame
  // (its dt layer); see core/temporal/temporal_window.h.
  std::vector<int> out;
  for (int p : positions_needed(int(job_frames.size()), job.reconstruction.window, /* hop = */ 0, pos))
    out.push_back(job_frames[size_t(p)]);
  return out;
}

namespace {

// ---- T-GPT stage 2 ----
// The window solutions are cached in `cache` (run_job keeps one for the whole
// shot; a stand-alone finalize uses a fresh one and re-solves the windows of
// its frame, with the same result).
// Adds the light seen directly from the camera to the solved image. The solve
// drops non-finite samples; `direct` bypasses it, so drop them here too (a
// corrupted farm file must not put NaN into the final image). Returns how
// many values were dropped.
//
// With `clamp`, the sum is clamped at 0: a least-squares solve rings around an
// outlier gradient (a glossy firefly) with negative lobes, and negative
// radiance is never the answer, so the clamp moves every such pixel closer to
// any reference (veach-mis, G-PT L2 at 32 spp: 8921 negative values, per-pixel
// relMSE 1.65 -> 0.87; docs/reconstruction.md). It makes the estimate
// consistent rather than unbiased (the mean of dark pixels rises), so jobs
// can turn it off (reconstruction.clamp_negative).
int64_t add_direct_clamped(const Image& direct, bool clamp, Image* final_image) {
  int64_t bad = 0;
  for (size_t k = 0; k < final_image->data().size(); ++k) {
    const float d = direct.data()[k];
    float& v = final_image->data()[k];
    if (std::isfinite(d)) v += d;
    else ++bad;
    if (clamp) v = std::max(v, 0.0f);
  }
  return bad;
}

// The stage-1 layers go into the output as they came, except values that are
// not finite (only a corrupted buffer file has them): zeroed and counted.
void zero_non_finite_layers(FrameOutput* out) {
  int64_t bad = 0;
  for (ImageLayer& l : out->image.layers)
    for (float& v : l.image.data())
      if (!std::isfinite(v)) v = 0.0f, ++bad;
  if (bad > 0) out->stats.left_out.push_back(std::to_string(bad) + " non-finite buffer values zeroed in the output layers");
}

Expected<FrameOutput> finalize_tgpt_frame(const JobSpec& job, int frame, const std::map<int, FrameBuffers>& buffers,
                                          const std::vector<int>& job_frames, TemporalWindowCache* cache) {
  auto settings = tgpt_settings_for(job);
  if (!settings.ok()) return settings.status();
  const int pos = frame_position(job_frames, frame);
  if (pos < 0) return invalid_argument("frame " + std::to_string(frame) + " is not in the job's frame range");
  const int n = int(job_frames.size());
  auto layers_at = [&](int p) -> const LayeredImage* {
    if (p < 0 || p >= n) return nullptr;
    auto it = buffers.find(job_frames[size_t(p)]);
    return it == buffers.end() ? nullptr : &it->second.layers;
  };
  // The frame and its successor must be here; the windows' other frames only
  // while their window is not solved yet (the cache reports what is missing).
  for (int p : {pos, pos + 1})
    if (p < n && !layers_at(p))
      return failed_precondition("finalize: frame " + std::to_string(frame) + " needs the buffers of frame " +
                                 std::to_string(job_frames[size_t(p)]));
  const FrameBuffers& fb = buffers.at(frame);
  const ImageLayer* direct = fb.layers.find("direct");
  if (!direct) return invalid_argument("finalize: frame buffers lack the 'direct' layer");

  ReconStats recon_stats;
  auto solved = cache->reconstruct(pos, layers_at, &recon_stats);
  if (!solved.ok()) return solved.status().with_context("frame " + std::to_string(frame) + ": reconstruction: ");
  Image final_image = std::move(solved.value());
  const int64_t bad_direct = add_direct_clamped(direct->image, job.reconstruction.clamp_negative, &final_image);

  FrameOutput out;
  out.frame = frame;
  out.stats = fb.stats;
  out.stats.reconstruct_seconds = recon_stats.seconds;
  if (bad_direct > 0)
    out.stats.left_out.push_back(std::to_string(bad_direct) + " non-finite direct-light values dropped");
  out.image.add("", {"R", "G", "B"}, std::move(final_image));
  auto add_estimate = [&](const char* name) -> Status {
    auto est = tgpt_frame_estimate(fb.layers, name);
    if (!est.ok()) return est.status();
    out.image.add(name, {"R", "G", "B"}, std::move(est.value()));
    return Status::Ok();
  };
  if (n == 1) {
    // A single-frame job never forms temporal buffers (issue 4): no dt layers.
    for (const char* name : {"primal", "dx", "dy"}) GDVR_RETURN_IF_ERROR(add_estimate(name));
    out.image.layers.push_back(*direct);
    for (const char* name : {"primal_var", "dx_var", "dy_var"}) GDVR_RETURN_IF_ERROR(add_estimate(name));
    if (const ImageLayer* l = fb.layers.find("shift_failure_rate")) out.image.layers.push_back(*l);
    copy_feature_layers(fb.layers, &out.image);
    out.stats.left_out.push_back("temporal gradients and buffers: single-frame job");
    zero_non_finite_layers(&out);
    return out;
  }
  // The frame's own temporal layers (towards the next frame of the job).
  TemporalGradients tg;
  if (const LayeredImage* next = layers_at(pos + 1)) {
    auto g = temporal_gradients(fb.layers, *next, settings.value());
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
  if (const ImageLayer* l = fb.layers.find("shift_failure_rate")) out.image.layers.push_back(*l);
  out.image.add("temporal_failure_rate", {"Y"}, std::move(tg.failure_rate));
  if (const ImageLayer* l = fb.layers.find("motion")) out.image.layers.push_back(*l);
  else out.image.add("motion", {"X", "Y", "V"}, Image(direct->image.width(), direct->image.height(), 3));
  copy_feature_layers(fb.layers, &out.image);
  if (settings->window == 1)
    out.stats.left_out.push_back("temporal terms in the solve: window of 1 frame (spatial reconstruction)");
  if (!settings->motion_vectors)
    out.stats.left_out.push_back("temporal masks: motion vectors off");
  if (recon_stats.total_non_finite() > 0)
    out.stats.left_out.push_back(std::to_string(recon_stats.total_non_finite()) +
                                 " non-finite constraints dropped by the reconstruction");
  zero_non_finite_layers(&out);
  return out;
}

}  // namespace

Expected<FrameOutput> finalize_frame(const JobSpec& job, int frame, const std::map<int, FrameBuffers>& buffers) {
  if (job.integrator == "tgpt") {
    auto frames = parse_frame_range(job.frames);
    if (!frames.ok()) return frames.status().with_context("job.frames: ");
    auto settings = tgpt_settings_for(job);
    if (!settings.ok()) return settings.status();
    TemporalWindowCache cache(settings.value(), int(frames->size()));
    return finalize_tgpt_frame(job, frame, buffers, frames.value(), &cache);
  }
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
  // the camera is kept out of the solve and added after it (docs/gpt.md,
  // "Direct light").
  auto method = parse_recon_method(job.reconstruction.method);
  if (!method.ok()) return method.status().with_context("job.reconstruction.");
  ReconSettings recon = GptSettings::defaults_for(ShiftMapping::kReconnect).recon;
  recon.method = method.value();
  recon.alpha = job.reconstruction.alpha;
  apply_term_weights(job.reconstruction, &recon);
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
  const int64_t bad_direct = add_direct_clamped(*layer("direct"), job.reconstruction.clamp_negative, &final_image);
  if (bad_direct > 0)
    out.stats.left_out.push_back(std::to_string(bad_direct) + " non-finite direct-light values dropped");
  out.image.add("", {"R", "G", "B"}, std::move(final_image));
  for (const ImageLayer& l : fb.layers.layers) out.image.layers.push_back(l);
  zero_non_finite_layers(&out);
  out.stats.reconstruct_seconds = solved->stats.seconds;
  if (solved->stats.total_non_finite() > 0)
    out.stats.left_out.push_back(std::to_string(solved->stats.total_non_finite()) +
                                 " non-finite constraints dropped by the reconstruction");
  return out;
}

Expected<std::unique_ptr<JobFinalizer>> JobFinalizer::create(const JobSpec& job) {
  std::unique_ptr<JobFinalizer> f(new JobFinalizer());
  f->job_ = job;
  if (job.integrator == "tgpt") {
    auto frames = parse_frame_range(job.frames);
    if (!frames.ok()) return frames.status().with_context("job.frames: ");
    auto settings = tgpt_settings_for(job);
    if (!settings.ok()) return settings.status();
    f->frames_ = std::move(frames.value());
    f->windows_ = std::make_unique<TemporalWindowCache>(settings.value(), int(f->frames_.size()));
  }
  return f;
}

JobFinalizer::~JobFinalizer() = default;

Expected<FrameOutput> JobFinalizer::finalize(int frame, const std::map<int, FrameBuffers>& buffers) {
  if (!windows_) return finalize_frame(job_, frame, buffers);
  auto out = finalize_tgpt_frame(job_, frame, buffers, frames_, windows_.get());
  // As the in-process run: windows that end at or before this frame are done
  // with while frames come in order.
  if (out.ok()) windows_->release_before(frame_position(frames_, frame) + 1);
  return out;
}

int JobFinalizer::windows_solved() const { return windows_ ? windows_->windows_solved() : 0; }

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
  std::vector<int> todo;  // frames to finalize, in order
  for (int f : job_frames)
    if (!skip.count(f)) todo.push_back(f);
  // Frames to render: everything a frame still to finalize reads (for tgpt its
  // windows, which may include already final frames after a resume).
  std::vector<std::vector<int>> needs;
  for (int f : todo) needs.push_back(frames_needed_to_finalize(job, job_frames, f));
  StreamSchedule schedule(todo, std::move(needs));
  // Progress counts rendered frames (the cost); for pt and gpt that is the
  // frames finalized, for tgpt the final frames trail by up to a window.
  const int render_count = int(schedule.render_order().size());
  const int already_done = int(job_frames.size() - todo.size());
  ProgressTracker progress(already_done + render_count, already_done, render_count, callbacks.on_progress);
  std::unique_ptr<TemporalWindowCache> windows;
  if (renderer.value()->prepared().tgpt)
    windows = std::make_unique<TemporalWindowCache>(renderer.value()->prepared().tgpt_settings, int(job_frames.size()));

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
    schedule.rendered(frame);
    progress.frame_done();
    for (int f = schedule.ready(); f >= 0; f = schedule.ready()) {
      auto out = windows ? finalize_tgpt_frame(job, f, buffers, job_frames, windows.get())
                         : finalize_frame(job, f, buffers);
      if (!out.ok()) return out.status();
      if (callbacks.on_frame_final) callbacks.on_frame_final(out.value());
      schedule.finalized();
      if (windows) windows->release_before(frame_position(job_frames, f) + 1);
    }
    std::vector<int> release;
    if (windows) {
      // tgpt: solved windows no longer need their frames' buffers.
      const int first =
          schedule.done() ? int(job_frames.size()) : frame_position(job_frames, todo[size_t(schedule.next_index())]);
      release = schedule.releasable(
          [&](int f) { return windows->buffers_needed(frame_position(job_frames, f), first); });
    } else {
      release = schedule.releasable();
    }
    for (int f : release) buffers.erase(f);
  }
  return Status::Ok();
}

}  // namespace gdvr
