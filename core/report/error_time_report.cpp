#include "core/report/error_time_report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "core/denoise/oidn_denoiser.h"
#include "core/io/color_transform.h"
#include "core/io/image_io.h"
#include "core/recon/predicted_improvement.h"
#include "core/image/error_metrics.h"
#include "core/render/feature_buffers.h"
#include "core/report/denoiser_comparison.h"
#include "core/report/plot.h"
#include "core/report/reference_noise.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

struct MethodSpec {
  std::string name;
  Integrator integrator;
  std::optional<ReconMethod> reconstruction;  // none for pt
  // PT with the stratified direct-light pass the gradient-domain methods use
  // (job.direct_light 4/16): the stronger baseline; plain `pt` is Mitsuba's estimator.
  bool direct_pass = false;
  // The frame denoised by OIDN guided by the feature buffers (albedo,
  // normal): the "path tracing + denoiser" users compare gdvr with. Needs a
  // build with OIDN (core/denoise/oidn_denoiser.h).
  bool denoised = false;
  // T-GPT with the sampled primal as its data term, not the job default
  // (denoised where this build has OIDN): what the denoised data term wins.
  bool sampled_data_term = false;
  // A comparison to ask for (--methods), not one of the default runs.
  bool only_when_asked = false;
};

const std::vector<MethodSpec>& all_methods() {
  static const std::vector<MethodSpec> kMethods = {
      {"pt", Integrator::kPt, std::nullopt},
      {"pt-sd", Integrator::kPt, std::nullopt, true},
      {"pt-oidn", Integrator::kPt, std::nullopt, false, true},
      {"pt-sd-oidn", Integrator::kPt, std::nullopt, true, true},
      {"gpt-l1", Integrator::kGpt, ReconMethod::kL1},
      {"gpt-l2", Integrator::kGpt, ReconMethod::kL2},
      {"gpt-weighted", Integrator::kGpt, ReconMethod::kWeighted},
      {"tgpt-l1", Integrator::kTgpt, ReconMethod::kL1},
      {"tgpt-l2", Integrator::kTgpt, ReconMethod::kL2},
      {"tgpt-l1-sampled", Integrator::kTgpt, ReconMethod::kL1, false, false, true, true},
      // tgpt-l1's frames denoised again by OIDN afterwards (Hua et al. 2019
      // found G-PT followed by a denoiser better than either): it imports
      // the denoiser's bias on texture (docs/benchmarks.md), so not the default.
      {"tgpt-l1-oidn", Integrator::kTgpt, ReconMethod::kL1, false, true, false, true},
  };
  return kMethods;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string format_frame(const std::string& pattern, int frame) {
  char buf[4096];
  std::snprintf(buf, sizeof(buf), pattern.c_str(), frame);
  return buf;
}

// A printf pattern with exactly one integer conversion (%d, %04d, ...).
bool is_frame_pattern(const std::string& s) {
  size_t p = s.find('%');
  if (p == std::string::npos) return false;
  size_t q = p + 1;
  while (q < s.size() && std::isdigit(static_cast<unsigned char>(s[q]))) ++q;
  return q < s.size() && s[q] == 'd' && s.find('%', q) == std::string::npos;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), f, v);
  return buf;
}

std::string budget_tag(double b) {
  std::string s = fmt("%g", b);
  std::replace(s.begin(), s.end(), '.', 'p');
  return s + "s";
}

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  if (!(in >> a >> b >> c)) return "unknown";
  return a + " " + b + " " + c;
}

// Display encoding for the report's images: the job's OCIO display/view, or a
// plain clamped sRGB curve when no config is given or it fails to load.
class Display {
 public:
  Display(const std::string& config, const OutputSpec& out, std::vector<std::string>* notes) {
    if (config.empty()) {
      notes->push_back("images: plain sRGB encoding (no OCIO config given)");
      return;
    }
    ColorTransformOptions o;
    o.config_path = config;
    o.display = out.ocio_display;
    o.view = out.ocio_view;
    auto t = ColorTransform::create(o);
    if (t.ok()) {
      transform_.emplace(std::move(t.value()));
      label_ = "OCIO " + o.view + " / " + o.display;
    } else {
      notes->push_back("images: OCIO transform unavailable (" + t.status().message() + "); plain sRGB used");
    }
  }
  Image apply(const Image& linear) const {
    if (transform_) {
      auto d = transform_->apply(linear);
      if (d.ok()) return std::move(d.value());
    }
    Image out(linear.width(), linear.height(), 3);
    for (int y = 0; y < linear.height(); ++y)
      for (int x = 0; x < linear.width(); ++x)
        for (int c = 0; c < 3; ++c) {
          float v = linear.at(x, y, c);
          v = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
          out.at(x, y, c) = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
        }
    return out;
  }
  const std::string& label() const { return label_; }

 private:
  std::optional<ColorTransform> transform_;
  std::string label_ = "sRGB (clamped)";
};

Image main_image(const LayeredImage& li) {
  if (const ImageLayer* l = li.find("")) return l->image;
  return Image();
}

// ---- Reference: supplied EXR(s) or high-spp PT, cached by key ----
struct Reference {
  std::map<int, Image> frames;
  // Per-pixel variance of each frame's mean (PT's `variance` layer), where the
  // reference has one: the source of its noise floor (core/report/reference_noise.h).
  std::map<int, Image> variances;
};

// The reference's noise floor from its variances; unknown (kNoValue) unless every frame has one.
ReferenceNoiseFloor noise_floor_of(const Reference& ref, const std::vector<int>& frames) {
  std::vector<const Image*> images, variances;
  for (int f : frames) {
    auto v = ref.variances.find(f);
    if (v == ref.variances.end()) return {};
    images.push_back(&ref.frames.at(f));
    variances.push_back(&v->second);
  }
  auto floor = reference_noise_floor(images, variances);
  return floor.ok() ? floor.value() : ReferenceNoiseFloor{};
}

Status load_supplied_reference(const ErrorTimeReportOptions& o, const std::vector<int>& frames, Reference* ref,
                               ReportMeta* meta) {
  const bool pattern = is_frame_pattern(o.reference);
  if (!pattern && frames.size() > 1)
    return invalid_argument("--reference '" + o.reference + "': " + std::to_string(frames.size()) +
                            " frames need a pattern with %d (e.g. ref_%04d.exr)");
  for (int f : frames) {
    const std::string path = pattern ? format_frame(o.reference, f) : o.reference;
    auto im = read_rgb_image(path);
    if (!im.ok()) return im.status().with_context("reference frame " + std::to_string(f) + ": ");
    ref->frames[f] = std::move(im.value());
    // A reference rendered by gdvr (or any EXR with a `variance` layer of the
    // mean) states its own noise.
    if (path.size() > 4 && path.compare(path.size() - 4, 4, ".exr") == 0) {
      auto layers = read_exr(path);
      if (layers.ok())
        if (const ImageLayer* v = layers->find("variance"))
          if (v->image.width() == ref->frames[f].width() && v->image.height() == ref->frames[f].height())
            ref->variances[f] = v->image;
    }
  }
  meta->reference_source = "supplied";
  meta->reference_path = o.reference;
  return Status::Ok();
}

Status build_reference(const ErrorTimeReportOptions& o, const std::vector<int>& frames, Reference* ref,
                       ReportMeta* meta, const std::function<void(const std::string&)>& log,
                       const std::atomic<bool>* cancel) {
  JobSpec rj = o.job;
  rj.integrator = Integrator::kPt;
  rj.spp = o.reference_spp;
  rj.time_budget_s = 0;
  rj.seed = o.job.seed ^ 0x9e3779b97f4a7c15ULL;  // independent of the PT runs' streams
  rj.reference.clear();
  // Emitters seen directly: a dense stratified pass (16×16 per pixel, 64×64
  // on emitter edges; unbiased, core/render/direct_emission.h). At a few
  // hundred random camera samples the edges of a small bright light would
  // otherwise dominate the reference's own error in the global relMSE.
  rj.direct_light = {16, 64};
  rj.frames = "0";
  // The key: the job as PT would render it (frames excluded: each frame is
  // cached on its own), where its scene resolves, and the scene file's bytes.
  std::string scene_path = rj.scene;
  if (fs::path(scene_path).is_relative())
    scene_path = (fs::path(!o.run.asset_root.empty() ? o.run.asset_root : o.run.base_dir) / scene_path).string();
  const std::string key = fnv1a_hex(job_to_json(rj) + "\n" + fs::absolute(scene_path).string() + "\n" +
                                    read_file(scene_path) + "\nspp=" + std::to_string(o.reference_spp));
  const fs::path dir = fs::path(o.out_dir) / "reference" / key;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return internal_error("cannot create '" + dir.string() + "': " + ec.message());
  auto frame_path = [&](int f) { return (dir / format_frame("frame_%04d.exr", f)).string(); };

  std::vector<int> missing;
  for (int f : frames)
    if (!fs::exists(frame_path(f))) missing.push_back(f);
  meta->reference_cached = missing.empty();
  meta->reference_spp = o.reference_spp;
  meta->reference_path = dir.string();
  meta->reference_source = "rendered: pt, " + std::to_string(o.reference_spp) + " spp, seed " + std::to_string(rj.seed) +
                           ", direct light 16x16 stratified (64x64 on emitter edges)";
  if (!missing.empty()) {
    std::string list;
    for (int f : missing) list += (list.empty() ? "" : ",") + std::to_string(f);
    rj.frames = list;
    if (log) log("reference: rendering " + std::to_string(missing.size()) + " frame(s) at " +
                 std::to_string(o.reference_spp) + " spp into " + dir.string());
    Status write_status;
    JobCallbacks cb;
    cb.on_frame_final = [&](const FrameOutput& out) {
      LayeredImage li;
      if (const ImageLayer* l = out.image.find("")) li.layers.push_back(*l);
      if (const ImageLayer* l = out.image.find("variance")) li.layers.push_back(*l);
      Status st = write_exr(frame_path(out.frame), li);
      if (!st.ok() && write_status.ok()) write_status = st;
      meta->reference_seconds += out.stats.render_seconds;
    };
    Status st = run_job(rj, o.run, cb, cancel);
    if (!st.ok()) return st.with_context("reference: ");
    GDVR_RETURN_IF_ERROR(write_status);
  }
  for (int f : frames) {
    auto li = read_exr(frame_path(f));
    if (!li.ok()) return li.status().with_context("reference cache: ");
    ref->frames[f] = main_image(li.value());
    if (ref->frames[f].empty()) return internal_error("reference cache '" + frame_path(f) + "' has no RGB layer");
    if (const ImageLayer* v = li->find("variance")) ref->variances[f] = v->image;
  }
  return Status::Ok();
}

// ---- Denoised baselines ----
struct DenoiseOverhead {
  double feature_seconds = 0, denoise_seconds = 0;
  double total() const { return feature_seconds + denoise_seconds; }
};

struct DenoisedFrame {
  Image image;
  double seconds = 0;
};

// `color` denoised by OIDN with the frame's albedo and normal guides.
Expected<DenoisedFrame> denoise_frame(const LayeredImage& frame, const Image& color, OidnDenoiser* denoiser) {
  const ImageLayer* albedo = frame.find(kAlbedoLayer);
  const ImageLayer* normal = frame.find(kNormalLayer);
  if (!albedo || !normal) return internal_error("the frame has no albedo and normal layers to guide the denoiser");
  if (!denoiser) return internal_error("no denoiser");
  const auto start = std::chrono::steady_clock::now();
  DenoiseInputs in;
  in.color = &color;
  in.albedo = &albedo->image;
  in.normal = &normal->image;
  auto out = denoiser->denoise(in);
  if (!out.ok()) return out.status();
  return DenoisedFrame{std::move(out.value()),
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
}

// The fixed cost per frame of a denoised method, measured on one frame of
// the job at 1 spp: its feature buffers, and one denoise after a first one
// that creates OIDN's filter (made once per report, not once per frame).
Expected<DenoiseOverhead> measure_denoise_overhead(const ErrorTimeReportOptions& o, int frame, OidnDenoiser* denoiser,
                                                   const std::atomic<bool>* cancel) {
  JobSpec job = o.job;
  job.integrator = Integrator::kPt;
  job.frames = std::to_string(frame);
  job.spp = 1;
  job.time_budget_s = 0;
  job.reference.clear();
  DenoiseOverhead overhead;
  Status frame_status = internal_error("measuring the denoiser's cost: no frame came back");
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& out) {
    overhead.feature_seconds = out.stats.feature_seconds;
    const Image color = main_image(out.image);
    for (int i = 0; i < 2; ++i) {
      auto d = denoise_frame(out.image, color, denoiser);
      if (!d.ok()) {
        frame_status = d.status();
        return;
      }
      overhead.denoise_seconds = d->seconds;
    }
    frame_status = Status::Ok();
  };
  GDVR_RETURN_IF_ERROR(run_job(job, o.run, cb, cancel));
  GDVR_RETURN_IF_ERROR(frame_status.with_context("measuring the denoiser's cost: "));
  return overhead;
}

// ---- One method at one budget ----
struct RunImages {
  std::map<int, Image> final_frames;  // every frame (flicker needs them all)
  LayeredImage display_layers;        // the display frame's failure maps
};

struct NoiseAccumulator {
  std::array<double, kTermCount> sum{};
  std::array<double, kTermCount> count{};
};

// What a denoised method does to each frame, and what that costs.
struct Denoising {
  OidnDenoiser* denoiser = nullptr;
  DenoiseOverhead overhead;
  FrameDenoiser for_jobs;  // the same device, lent to T-GPT's data term
};

Status run_method(const ErrorTimeReportOptions& o, const MethodSpec& m, double budget, const std::vector<int>& frames,
                  int display_frame, const Reference& ref, const Denoising& denoising, ReportRow* row,
                  RunImages* images, const std::function<void(double)>& progress, const std::atomic<bool>* cancel) {
  JobSpec job = o.job;
  job.integrator = m.integrator;
  if (m.reconstruction) job.reconstruction.method = *m.reconstruction;
  if (m.direct_pass) job.direct_light = {4, 16};
  // Equal time: every method gets the whole budget, and the job's time
  // budget (core/job/frame_time_budget.h) pays its fixed costs out of it as
  // it does for any job: the feature pass, the reconstruction and, for the
  // denoised methods, the denoiser, which run_job measures as the work this
  // report's callback does per final frame (the overhead measured before the
  // runs is its guess until the first frame is out). Sampling gets the rest,
  // at least one pass.
  job.time_budget_s = budget;
  job.spp = 0;  // the budget picks the count, in passes of 1 spp
  JobRunOptions run = o.run;
  run.caller_seconds_per_frame = m.denoised ? denoising.overhead.denoise_seconds : 0;
  job.reference.clear();
  // Only the denoised methods read the feature buffers: the others leave
  // them out (an EXR layer selection without them skips their pass).
  if (!m.denoised) job.outputs.exr_layers = {"primal"};
  // T-GPT's data term as a job gets it: denoised when this build has OIDN
  // (the job default), unless the method asks for the sampled one.
  if (m.sampled_data_term) job.reconstruction.data_term = DataTerm::kSampled;
  if (m.integrator == Integrator::kTgpt && !m.sampled_data_term) run.denoiser = denoising.for_jobs;

  row->method = m.name;
  row->integrator = integrator_name(m.integrator);
  row->reconstruction = m.reconstruction ? recon_method_name(*m.reconstruction) : "";
  row->budget_s = budget;
  RelMseSums total, primal_total;
  bool have_primal = false;
  double shift_fail = 0, temporal_fail = 0;
  int shift_n = 0, temporal_n = 0;
  NoiseAccumulator noise;
  Status metric_status;

  JobCallbacks cb;
  cb.on_progress = [&](const JobProgress& p) {
    if (progress) progress(p.fraction);
  };
  cb.on_frame_final = [&](const FrameOutput& out) {
    if (!metric_status.ok()) return;
    const FrameStats& s = out.stats;
    Image img = main_image(out.image);
    auto it = ref.frames.find(out.frame);
    if (it == ref.frames.end() || img.empty()) {
      metric_status = internal_error("frame " + std::to_string(out.frame) + ": no image or no reference");
      return;
    }
    if (m.denoised) {
      auto denoised = denoise_frame(out.image, img, denoising.denoiser);
      if (!denoised.ok()) {
        metric_status = denoised.status().with_context("frame " + std::to_string(out.frame) + ": ");
        return;
      }
      img = std::move(denoised->image);
      row->denoise_seconds += denoised->seconds;
    }
    auto sums = rel_mse_sums(img, it->second);
    if (!sums.ok()) {
      metric_status = sums.status().with_context("frame " + std::to_string(out.frame) + ": ");
      return;
    }
    total.add(sums.value());
    row->frame_numbers.push_back(out.frame);
    row->frame_rel_mse_global.push_back(sums->global());
    row->frame_rel_mse_per_pixel.push_back(sums->per_pixel());
    row->frames += 1;
    row->render_seconds += s.render_seconds;
    row->feature_seconds += s.feature_seconds;
    row->stage1_seconds += s.stage1_seconds;
    row->reconstruct_seconds += s.reconstruct_seconds;
    row->spp += s.spp;
    for (const std::string& l : s.left_out) row->left_out[l] += 1;
    // Unreconstructed estimate of the same samples: primal + direct.
    const ImageLayer* primal = out.image.find("primal");
    const ImageLayer* direct = out.image.find("direct");
    if (is_gradient_domain(m.integrator) && primal && direct && primal->image.data().size() == direct->image.data().size()) {
      Image raw = primal->image;
      for (size_t k = 0; k < raw.data().size(); ++k) raw.data()[k] += direct->image.data()[k];
      auto ps = rel_mse_sums(raw, it->second);
      if (ps.ok()) {
        primal_total.add(ps.value());
        have_primal = true;
      }
    }
    if (const ImageLayer* l = out.image.find("shift_failure_rate")) shift_fail += mean_finite(l->image), ++shift_n;
    // The last frame has no next frame: its temporal layers are zero, not measured.
    const bool has_next = out.frame != frames.back();
    if (const ImageLayer* l = out.image.find("temporal_failure_rate"); l && has_next)
      temporal_fail += mean_finite(l->image), ++temporal_n;
    for (Term t : kAllTerms) {
      if (is_temporal(t) && (m.integrator != Integrator::kTgpt || !has_next)) continue;
      const ImageLayer* l = out.image.find(std::string(term_name(t)) + "_var");
      if (!l) continue;
      for (float v : l->image.data())
        if (std::isfinite(v) && v >= 0) noise.sum[term_index(t)] += v, noise.count[term_index(t)] += 1;
    }
    if (out.frame == display_frame) {
      for (const char* name : {"shift_failure_rate", "temporal_failure_rate"})
        if (const ImageLayer* l = out.image.find(name)) images->display_layers.layers.push_back(*l);
    }
    images->final_frames[out.frame] = std::move(img);
  };
  const auto run_start = std::chrono::steady_clock::now();
  Status st = run_job(job, run, cb, cancel);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start).count();
  if (!st.ok()) return st;
  GDVR_RETURN_IF_ERROR(metric_status);
  if (row->frames == 0) return internal_error(m.name + ": no frames came back");

  const double n = row->frames;
  row->render_seconds /= n;
  row->feature_seconds /= n;
  row->stage1_seconds /= n;
  row->reconstruct_seconds /= n;
  row->denoise_seconds /= n;
  row->spp /= n;
  // One accounting for every method, the one the budget pays: stage 1 (render,
  // features, moving the scene), stage 2, the denoiser.
  row->seconds_per_frame = row->stage1_seconds + row->reconstruct_seconds + row->denoise_seconds;
  row->wall_seconds_per_frame = wall / n;
  row->rel_mse_global = total.global();
  double pp = 0;
  for (double v : row->frame_rel_mse_per_pixel) pp += v;
  row->rel_mse_per_pixel = pp / n;
  row->non_finite = total.non_finite;
  if (shift_n) row->shift_failure_rate = shift_fail / shift_n;
  if (temporal_n) row->temporal_failure_rate = temporal_fail / temporal_n;
  if (frames.size() > 1) {
    std::vector<const Image*> imgs, refs;
    for (int f : frames) {
      auto a = images->final_frames.find(f);
      auto b = ref.frames.find(f);
      if (a == images->final_frames.end() || b == ref.frames.end()) continue;
      imgs.push_back(&a->second);
      refs.push_back(&b->second);
    }
    auto fl = temporal_flicker(imgs, refs);
    if (fl.ok()) row->flicker = fl.value();
  }
  if (have_primal && total.global() > 0) row->achieved_improvement = primal_total.global() / total.global();
  if (is_gradient_domain(m.integrator)) {
    NoiseLevels levels;
    for (Term t : kAllTerms)
      levels[t] = noise.count[term_index(t)] > 0 ? noise.sum[term_index(t)] / noise.count[term_index(t)] : 0.0;
    ReconSettings s;
    s.method = ReconMethod::kL2;
    s.alpha = job.reconstruction.alpha;
    auto pred = predicted_improvement(levels, s, /* temporal = */ m.integrator == Integrator::kTgpt);
    if (pred.ok()) row->predicted_improvement = pred.value();
  }
  return Status::Ok();
}

// ---- Output: plots, images, HTML ----
std::vector<PlotSeries> series_of(const std::vector<ReportRow>& rows, const std::vector<std::string>& methods,
                                  double ReportRow::*field) {
  std::vector<PlotSeries> out;
  for (size_t i = 0; i < methods.size(); ++i) {
    PlotSeries s;
    s.name = methods[i];
    s.color = plot_color(int(i));
    for (const ReportRow& r : rows)
      if (r.method == methods[i]) s.points.push_back({r.seconds_per_frame, r.*field});
    out.push_back(std::move(s));
  }
  return out;
}

std::string cell(double v, const char* f = "%.4g") { return std::isfinite(v) ? fmt(f, v) : "&ndash;"; }

std::string legend_html(const std::vector<std::string>& methods) {
  std::string h = "<p class=legend>";
  for (size_t i = 0; i < methods.size(); ++i)
    h += "<span><i style=\"background:" + css_color(plot_color(int(i))) + "\"></i>" + html_escape(methods[i]) + "</span> ";
  return h + "</p>\n";
}

std::string html_report(const ErrorTimeReportOptions& o, const ReportMeta& meta, const std::vector<ReportRow>& rows,
                        const std::vector<std::string>& methods, const std::vector<double>& budgets, int display_frame,
                        bool animated, const std::map<std::string, std::string>& images,
                        const std::string& display_label) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>gdvr error-vs-time report</title>\n<style>"
       "body{font-family:sans-serif;margin:1.5em;max-width:1400px}table{border-collapse:collapse;margin:.5em 0}"
       "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right;font-size:13px}th{background:#eee}"
       "td.l{text-align:left}.legend span{margin-right:1em}.legend i{display:inline-block;width:14px;height:14px;"
       "margin-right:4px;vertical-align:middle}figure{display:inline-block;margin:4px;text-align:center}"
       "figure img{width:220px;image-rendering:pixelated}figcaption{font-size:12px}.good{color:#070}.bad{color:#a00}"
       "</style></head><body>\n";
  h << "<h1>Error against time</h1>\n<table>\n";
  auto info = [&](const std::string& k, const std::string& v) {
    h << "<tr><th>" << k << "</th><td class=l>" << html_escape(v) << "</td></tr>\n";
  };
  info("input", meta.input);
  info("frames", meta.frames + (animated ? " (animation)" : " (still)"));
  info("resolution", std::to_string(meta.width) + " x " + std::to_string(meta.height));
  info("reference", meta.reference_source + (meta.reference_cached ? " (cached)" : "") + " — " + meta.reference_path);
  info("threads", meta.threads > 0 ? std::to_string(meta.threads) : "all cores");
  info("load average at start", meta.load);
  info("budgets (s per frame)", [&] {
    std::string s;
    for (double b : budgets) s += (s.empty() ? "" : ", ") + fmt("%g", b);
    return s;
  }());
  info("images", display_label + ", frame " + std::to_string(display_frame));
  h << "</table>\n";
  if (!meta.notes.empty()) {
    h << "<ul>\n";
    for (const auto& n : meta.notes) h << "<li>" << html_escape(n) << "</li>\n";
    h << "</ul>\n";
  }
  // ---- Plots ----
  h << "<h2>relMSE against time (log-log)</h2>\n" << legend_html(methods);
  h << "<figure><img style=\"width:640px\" src=\"plot_relmse_global.png\" alt=\"global relMSE vs seconds\">"
       "<figcaption>global relMSE &Vert;I&minus;R&Vert;&sup2;/&Vert;R&Vert;&sup2; vs seconds per frame</figcaption></figure>\n";
  h << "<figure><img style=\"width:640px\" src=\"plot_relmse_per_pixel.png\" alt=\"per-pixel relMSE vs seconds\">"
       "<figcaption>per-pixel relMSE mean((I&minus;R)&sup2;/(R&sup2;+0.01)) vs seconds per frame</figcaption></figure>\n";
  if (animated)
    h << "<h2>Temporal flicker against time (log-log)</h2>\n"
      << "<figure><img style=\"width:640px\" src=\"plot_flicker.png\" alt=\"flicker vs seconds\"><figcaption>"
         "mean squared frame-to-frame change of (result &minus; reference) vs seconds per frame</figcaption></figure>\n";
  // ---- Table ----
  h << "<h2>Equal-time comparison</h2>\n<p>Ratio = PT's relMSE at the same budget / the method's (&gt; 1: the method "
       "beats PT). &ldquo;interp.&rdquo; compares with PT's curve interpolated at the method's measured seconds "
       "(reconstruction time included). s/frame: what the budget pays for (render, features, reconstruction, "
       "denoising); wall: the run's wall time per frame (scene loading and the report's measuring too).</p>\n"
       "<table><tr><th>method</th><th>budget s</th><th>s/frame</th><th>wall s/frame</th><th>spp</th>"
       "<th>relMSE global</th><th>relMSE per-pixel</th><th>ratio global</th><th>ratio per-pixel</th>"
       "<th>ratio interp.</th><th>flicker</th><th>shift failures</th><th>temporal failures</th></tr>\n";
  for (const ReportRow& r : rows) {
    auto ratio_cell = [&](double v) {
      if (!std::isfinite(v)) return std::string("<td>&ndash;</td>");
      return std::string("<td class=") + (v >= 1 ? "good" : "bad") + ">" + fmt("%.3g", v) + "</td>";
    };
    h << "<tr><td class=l>" << html_escape(r.method) << "</td><td>" << cell(r.budget_s, "%g") << "</td><td>"
      << cell(r.seconds_per_frame, "%.3f") << "</td><td>" << cell(r.wall_seconds_per_frame, "%.3f") << "</td><td>"
      << cell(r.spp, "%.1f") << "</td><td>"
      << cell(r.rel_mse_global) << "</td><td>" << cell(r.rel_mse_per_pixel) << "</td>"
      << (r.method == "pt" ? "<td>1</td><td>1</td><td>&ndash;</td>"
                           : ratio_cell(r.equal_time_ratio_global) + ratio_cell(r.equal_time_ratio_per_pixel) +
                                 ratio_cell(r.equal_time_ratio_interpolated))
      << "<td>" << cell(r.flicker) << "</td><td>" << cell(r.shift_failure_rate, "%.3f") << "</td><td>"
      << cell(r.temporal_failure_rate, "%.3f") << "</td></tr>\n";
  }
  h << "</table>\n";
  // ---- Against the denoiser ----
  const std::vector<DenoiserComparison> vs_denoiser = compare_with_denoisers(rows, meta.reference_floor);
  if (!vs_denoiser.empty()) {
    const DenoiserTargets targets;
    h << "<h2>Against the best denoised path tracing</h2>\n<p>Each gradient-domain method over the better of "
         "pt-oidn and pt-sd-oidn at the same budget, figure by figure (&lt; 1: the method wins). Targets: per-pixel "
         "&le; " << fmt("%g", targets.per_pixel) << "&times;, flicker &le; " << fmt("%g", targets.flicker)
      << "&times;, global &le; " << fmt("%g", targets.global) << "&times;, at no more than "
      << fmt("%g", 1 + targets.time_tolerance) << "&times; the baseline's time, with the reference's own noise at most "
      << fmt("%g", targets.floor_fraction) << "&times; every figure compared (per-pixel "
      << cell(meta.reference_floor.per_pixel) << ", flicker " << cell(meta.reference_floor.flicker) << ", global "
      << cell(meta.reference_floor.global) << ").</p>\n<table><tr><th>method</th><th>budget s</th><th>best per-pixel "
         "baseline</th><th>time</th><th>per-pixel</th><th>flicker</th><th>global</th><th>reference floor</th>"
         "<th>verdict</th><th>floor removed: per-pixel / flicker / global</th></tr>\n";
    auto mark = [&](double v, bool ok) { return cell(v, "%.2f") + (ok ? " &#10003;" : " &#10007;"); };
    for (const DenoiserComparison& c : vs_denoiser)
      h << "<tr><td class=l>" << html_escape(c.method) << "</td><td>" << cell(c.budget_s, "%g") << "</td><td class=l>"
        << c.baseline << "</td><td>" << mark(c.seconds_ratio, c.equal_time) << "</td><td>"
        << mark(c.ratio_per_pixel, c.meets_per_pixel) << "</td><td>" << mark(c.ratio_flicker, c.meets_flicker)
        << "</td><td>" << mark(c.ratio_global, c.meets_global) << "</td><td class=l>"
        << (c.floor_well_below ? "well below" : "too close") << "</td><td class=l>"
        << (c.meets_all() ? "meets" : "misses") << "</td><td>" << cell(c.floor_removed_per_pixel, "%.2f") << " / "
        << cell(c.floor_removed_flicker, "%.2f") << " / " << cell(c.floor_removed_global, "%.2f") << "</td></tr>\n";
    h << "</table>\n";
  }
  // ---- Predicted vs achieved ----
  h << "<h2>Predicted against achieved improvement</h2>\n<p>Reconstruction against its own primal (+ direct light), "
       "same samples. Predicted: the frequency-domain model of Kettunen et al. 2015 (docs/reconstruction.md) from the "
       "measured mean variances of the buffers (L2 model, "
       "white noise; " << (animated ? "temporal terms included for T-GPT" : "spatial") << "). Achieved: global "
       "relMSE of primal + direct over that of the result. A large shortfall points at a broken shift, a bad solver "
       "or an error dominated by the reference's own noise.</p>\n<table><tr><th>method</th><th>budget s</th>"
       "<th>predicted</th><th>achieved</th><th>achieved / predicted</th></tr>\n";
  for (const ReportRow& r : rows) {
    if (r.integrator == "pt") continue;
    const double q = std::isfinite(r.predicted_improvement) && std::isfinite(r.achieved_improvement)
                         ? r.achieved_improvement / r.predicted_improvement
                         : kNoValue;
    h << "<tr><td class=l>" << html_escape(r.method) << "</td><td>" << cell(r.budget_s, "%g") << "</td><td>"
      << cell(r.predicted_improvement, "%.3g") << "</td><td>" << cell(r.achieved_improvement, "%.3g") << "</td><td>"
      << cell(q, "%.2f") << "</td></tr>\n";
  }
  h << "</table>\n";
  // ---- Images ----
  h << "<h2>Images at equal time (frame " << display_frame << ")</h2>\n";
  for (double b : budgets) {
    h << "<h3>" << fmt("%g", b) << " s per frame</h3>\n<div>";
    auto fig = [&](const std::string& key, const std::string& caption) {
      auto it = images.find(key);
      if (it == images.end()) return;
      h << "<figure><img src=\"" << html_escape(it->second) << "\" alt=\"" << html_escape(key) << "\"><figcaption>"
        << caption << "</figcaption></figure>";
    };
    fig("reference", "reference");
    for (const std::string& m : methods) {
      std::string cap = html_escape(m);
      for (const ReportRow& r : rows)
        if (r.method == m && r.budget_s == b) cap += "<br>relMSE " + cell(r.rel_mse_global) + ", " + cell(r.spp, "%.0f") + " spp";
      fig(m + "@" + budget_tag(b), cap);
    }
    h << "</div>\n";
  }
  h << "<h2>Shift-failure heat maps (frame " << display_frame << ", largest budget)</h2>\n<p>black 0 &rarr; red "
       "&rarr; yellow &rarr; white 1 (fraction of offset paths whose shift failed); blue: not finite.</p>\n<div>";
  for (const std::string& m : methods)
    for (const char* kind : {"shift", "temporal"}) {
      auto it = images.find(m + "#" + kind);
      if (it != images.end())
        h << "<figure><img src=\"" << html_escape(it->second) << "\" alt=\"" << kind << "\"><figcaption>"
          << html_escape(m) << " " << kind << "</figcaption></figure>";
    }
  h << "</div>\n";
  // ---- Left out ----
  h << "<h2>What the pipeline left out</h2>\n<table><tr><th>method</th><th>budget s</th><th>left out (frames)</th></tr>\n";
  for (const ReportRow& r : rows) {
    std::string s;
    for (const auto& [what, count] : r.left_out)
      s += html_escape(what) + " (" + std::to_string(count) + "/" + std::to_string(r.frames) + ")<br>";
    h << "<tr><td class=l>" << html_escape(r.method) << "</td><td>" << cell(r.budget_s, "%g") << "</td><td class=l>"
      << (s.empty() ? "nothing" : s) << "</td></tr>\n";
  }
  h << "</table>\n<p>Data: <a href=\"results.csv\">results.csv</a>, <a href=\"results.json\">results.json</a>. "
    << "Generated by gdvr-report from " << html_escape(o.input_name) << ".</p>\n</body></html>\n";
  return h.str();
}

}  // namespace

const std::vector<std::string>& report_method_names() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> n;
    for (const MethodSpec& m : all_methods()) n.push_back(m.name);
    return n;
  }();
  return kNames;
}

std::string fnv1a_hex(const std::string& data) {
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : data) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char buf[20];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

Expected<ErrorTimeReport> run_error_time_report(const ErrorTimeReportOptions& o,
                                                const std::function<void(const std::string&)>& log,
                                                const std::atomic<bool>* cancel) {
  if (o.out_dir.empty()) return invalid_argument("report: no output folder given");
  if (o.budgets.empty()) return invalid_argument("report: no time budgets given");
  for (double b : o.budgets)
    if (!(b > 0) || !std::isfinite(b)) return invalid_argument("report: budgets must be positive seconds (got " + fmt("%g", b) + ")");
  if (o.reference.empty() && o.reference_spp < 1) return invalid_argument("report: --reference-spp must be at least 1");

  ErrorTimeReport report;
  ReportMeta& meta = report.meta;
  meta.input = o.input_name;
  meta.frames = o.job.frames;
  meta.threads = o.run.threads;
  meta.load = load_average();

  JobSpec pt_job = o.job;
  pt_job.integrator = Integrator::kPt;
  GDVR_RETURN_IF_ERROR(validate_job(pt_job, o.run));
  auto frames_or = parse_frame_range(o.job.frames);
  if (!frames_or.ok()) return frames_or.status().with_context("job.frames: ");
  const std::vector<int> frames = frames_or.value();
  const bool animated = frames.size() > 1;

  // ---- Methods ----
  // OIDN's device for the denoised methods: made when one is asked for (all
  // are, by default, in a build with OIDN); a build without it offers none.
  std::shared_ptr<OidnDenoiser> denoiser;
  Status denoiser_status = Status::Ok();
  std::vector<MethodSpec> methods;
  for (const MethodSpec& m : all_methods()) {
    const bool requested = std::find(o.methods.begin(), o.methods.end(), m.name) != o.methods.end();
    if (!o.methods.empty() && !requested) continue;
    if (o.methods.empty() && m.only_when_asked) continue;
    // T-GPT's default data term uses the denoiser where there is one, and
    // runs without it (sampled, said in its notes) where there is none.
    const bool uses_denoiser = m.integrator == Integrator::kTgpt && !m.sampled_data_term;
    if ((m.denoised || uses_denoiser) && !denoiser && denoiser_status.ok()) {
      OidnDenoiserSettings ds;
      ds.threads = o.run.threads;
      auto d = OidnDenoiser::create(ds);
      if (d.ok()) denoiser = std::move(d.value());
      else denoiser_status = d.status();
    }
    if (m.denoised) {
      if (!denoiser) {
        if (requested) return Status(denoiser_status.code(), "report: " + m.name + ": " + denoiser_status.message());
        meta.notes.push_back(m.name + ": not run (" +
                             (denoiser_status.code() == StatusCode::kUnimplemented
                                  ? std::string("this build has no Intel Open Image Denoise")
                                  : denoiser_status.message()) +
                             ")");
        continue;
      }
    }
    if (m.integrator == Integrator::kTgpt) {
      if (!animated) {
        if (!o.methods.empty()) meta.notes.push_back(m.name + ": skipped, a still (T-GPT needs 2+ frames)");
        continue;
      }
      JobSpec t = o.job;
      t.integrator = Integrator::kTgpt;
      t.reconstruction.method = *m.reconstruction;
      Status st = validate_job(t, o.run);
      if (!st.ok()) {
        meta.notes.push_back(m.name + ": not available (" + st.message() + ")");
        continue;
      }
    }
    methods.push_back(m);
  }
  for (const std::string& want : o.methods)
    if (std::find(report_method_names().begin(), report_method_names().end(), want) == report_method_names().end())
    {
      std::string known;
      for (const std::string& n : report_method_names()) known += (known.empty() ? "" : ", ") + n;
      return invalid_argument("report: unknown method '" + want + "' (known: " + known + ")");
    }
  if (methods.empty()) return invalid_argument("report: no method left to run");
  if (std::none_of(methods.begin(), methods.end(), [](const MethodSpec& m) { return m.name == "pt"; }))
    meta.notes.push_back("pt not run: no equal-time ratios");

  std::error_code ec;
  fs::create_directories(fs::path(o.out_dir) / "images", ec);
  if (ec) return internal_error("cannot create '" + o.out_dir + "/images': " + ec.message());

  // ---- Reference ----
  Reference ref;
  if (!o.reference.empty()) {
    GDVR_RETURN_IF_ERROR(load_supplied_reference(o, frames, &ref, &meta));
  } else {
    GDVR_RETURN_IF_ERROR(build_reference(o, frames, &ref, &meta, log, cancel));
  }
  const Image& first_ref = ref.frames.at(frames.front());
  meta.width = first_ref.width();
  meta.height = first_ref.height();
  meta.reference_floor = noise_floor_of(ref, frames);
  if (std::isfinite(meta.reference_floor.global))
    meta.notes.push_back("the reference's own noise adds about " + fmt("%.3g", meta.reference_floor.global) +
                         " to every global relMSE, " + fmt("%.3g", meta.reference_floor.per_pixel) +
                         " to every per-pixel relMSE" +
                         (std::isfinite(meta.reference_floor.flicker)
                              ? ", " + fmt("%.3g", meta.reference_floor.flicker) + " to every flicker"
                              : std::string()) +
                         " (from its variance of the mean)");

  const int display_frame = frames[frames.size() / 2];
  Denoising denoising;
  denoising.denoiser = denoiser.get();
  if (denoiser) denoising.for_jobs = oidn_frame_denoiser(denoiser);
  // The denoised baselines' fixed cost (T-GPT's data term is stage 1's own).
  if (denoiser && std::any_of(methods.begin(), methods.end(), [](const MethodSpec& m) { return m.denoised; })) {
    auto overhead = measure_denoise_overhead(o, frames.front(), denoiser.get(), cancel);
    if (!overhead.ok()) return overhead.status().with_context("report: ");
    denoising.overhead = overhead.value();
    meta.notes.push_back("denoised methods: features " + fmt("%.3f", overhead->feature_seconds) + " s + OIDN " +
                         fmt("%.3f", overhead->denoise_seconds) +
                         " s per frame (measured on frame " + std::to_string(frames.front()) +
                         "), paid from each budget (measured again every frame)");
    for (double b : o.budgets)
      if (overhead->total() >= b)
        meta.notes.push_back("denoised methods at " + fmt("%g", b) + " s: features and denoising alone take longer; "
                             "one 1-spp pass, over the budget");
  }
  std::vector<double> budgets = o.budgets;
  std::sort(budgets.begin(), budgets.end());
  budgets.erase(std::unique(budgets.begin(), budgets.end()), budgets.end());
  std::vector<std::string> method_names;
  for (const MethodSpec& m : methods) method_names.push_back(m.name);

  Display display(o.ocio_config, o.job.outputs, &meta.notes);
  std::map<std::string, std::string> images;  // key -> path relative to out_dir
  auto save_png = [&](const std::string& rel, const Image& display_rgb) -> Status {
    GDVR_RETURN_IF_ERROR(write_png8((fs::path(o.out_dir) / rel).string(), display_rgb));
    return Status::Ok();
  };
  GDVR_RETURN_IF_ERROR(save_png("images/reference.png", display.apply(ref.frames.at(display_frame))));
  images["reference"] = "images/reference.png";

  auto write_results = [&]() -> Status {
    std::vector<ReportRow> rows = report.rows;
    fill_equal_time_ratios(&rows);
    GDVR_RETURN_IF_ERROR(write_text_file((fs::path(o.out_dir) / "results.csv").string(), results_csv(rows)));
    GDVR_RETURN_IF_ERROR(write_text_file((fs::path(o.out_dir) / "results.json").string(), results_json(meta, rows)));
    return Status::Ok();
  };

  // ---- Runs: every budget, every method ----
  const int total_runs = int(budgets.size() * methods.size());
  int run_index = 0;
  for (double b : budgets) {
    for (const MethodSpec& m : methods) {
      ++run_index;
      const std::string what = "[" + std::to_string(run_index) + "/" + std::to_string(total_runs) + "] " + m.name +
                               " at " + fmt("%g", b) + " s/frame";
      auto last = std::chrono::steady_clock::now() - std::chrono::seconds(1);
      auto progress = [&](double f) {
        auto now = std::chrono::steady_clock::now();
        if (!log || now - last < std::chrono::milliseconds(500)) return;
        last = now;
        log(what + ": " + fmt("%.0f", f * 100) + "%");
      };
      ReportRow row;
      RunImages run_images;
      Status st = run_method(o, m, b, frames, display_frame, ref, denoising, &row, &run_images, progress, cancel);
      if (!st.ok()) {
        if (st.code() == StatusCode::kCancelled) GDVR_RETURN_IF_ERROR(write_results());
        return st.with_context(m.name + " at " + fmt("%g", b) + " s: ");
      }
      if (log)
        log(what + ": " + fmt("%.2f", row.seconds_per_frame) + " s/frame, " + fmt("%.1f", row.spp) + " spp, relMSE " +
            fmt("%.4g", row.rel_mse_global) + " (per-pixel " + fmt("%.4g", row.rel_mse_per_pixel) + ")");
      const std::string tag = m.name + "_" + budget_tag(b);
      auto it = run_images.final_frames.find(display_frame);
      if (it != run_images.final_frames.end()) {
        GDVR_RETURN_IF_ERROR(save_png("images/" + tag + ".png", display.apply(it->second)));
        images[m.name + "@" + budget_tag(b)] = "images/" + tag + ".png";
      }
      if (b == budgets.back()) {
        for (const auto& [layer, kind] : {std::pair<const char*, const char*>{"shift_failure_rate", "shift"},
                                          {"temporal_failure_rate", "temporal"}}) {
          if (const ImageLayer* l = run_images.display_layers.find(layer)) {
            const std::string rel = "images/" + m.name + "_" + kind + "_failures.png";
            GDVR_RETURN_IF_ERROR(save_png(rel, heat_map(l->image)));
            images[m.name + "#" + kind] = rel;
          }
        }
      }
      report.rows.push_back(std::move(row));
      GDVR_RETURN_IF_ERROR(write_results());
    }
  }
  fill_equal_time_ratios(&report.rows);

  // ---- Plots and HTML ----
  PlotOptions po;
  GDVR_RETURN_IF_ERROR(save_png("plot_relmse_global.png",
                                render_plot(series_of(report.rows, method_names, &ReportRow::rel_mse_global), po)));
  GDVR_RETURN_IF_ERROR(save_png("plot_relmse_per_pixel.png",
                                render_plot(series_of(report.rows, method_names, &ReportRow::rel_mse_per_pixel), po)));
  if (animated)
    GDVR_RETURN_IF_ERROR(
        save_png("plot_flicker.png", render_plot(series_of(report.rows, method_names, &ReportRow::flicker), po)));
  GDVR_RETURN_IF_ERROR(write_results());
  report.html_path = (fs::path(o.out_dir) / "report.html").string();
  GDVR_RETURN_IF_ERROR(write_text_file(report.html_path, html_report(o, meta, report.rows, method_names, budgets,
                                                                     display_frame, animated, images, display.label())));
  return report;
}

}  // namespace gdvr
