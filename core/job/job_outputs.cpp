#include "core/job/job_outputs.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>

#include <nlohmann/json.hpp>

#include "core/io/atomic_file.h"
#include "core/io/image_io.h"
#include "core/io/shipped_ocio_config.h"
#include "core/image/error_metrics.h"
#include "core/render/feature_buffers.h"
#include "core/util/path_confinement.h"

namespace gdvr {
namespace fs = std::filesystem;

namespace {

bool wants_video(const JobSpec& job) { return job.outputs.video_codec != "none"; }
bool wants_display(const JobSpec& job) { return job.outputs.previews || wants_video(job); }

ColorTransformOptions transform_options(const JobSpec& job, const std::string& ocio_config) {
  ColorTransformOptions o;
  o.config_path = resolve_ocio_config_path(ocio_config.empty() ? find_shipped_ocio_config() : ocio_config);
  if (!job.outputs.ocio_display.empty()) o.display = job.outputs.ocio_display;
  if (!job.outputs.ocio_view.empty()) o.view = job.outputs.ocio_view;
  return o;
}

// The job's fps as the rational FFmpeg wants: NTSC rates (23.976, 29.97,
// 59.94) become n*1000/1001 exactly rather than a rounded millirate.
void fps_rational(double fps, int* num, int* den) {
  if (std::abs(fps - std::round(fps)) < 1e-6) {
    *num = int(std::round(fps)), *den = 1;
  } else if (double ntsc = fps * 1.001; std::abs(ntsc - std::round(ntsc)) < 1e-3) {
    *num = int(std::round(ntsc)) * 1000, *den = 1001;
  } else {
    *num = int(std::round(fps * 1000)), *den = 1000;
  }
}

Status with_field(const Status& st, const std::string& field) {
  return st.ok() ? st : Status(st.code(), field + ": " + st.message());
}

std::string numbered(const char* pattern, int frame) {
  char buf[48];
  std::snprintf(buf, sizeof buf, pattern, frame);
  return buf;
}

nlohmann::ordered_json frame_json(const WrittenFrame& r) {
  const FrameStats& s = r.stats;
  return {{"frame", s.frame},
          {"file", r.file},
          {"bytes", r.bytes},
          {"render_seconds", s.render_seconds},
          {"reconstruct_seconds", s.reconstruct_seconds},
          {"feature_seconds", s.feature_seconds},
          {"sampling_seconds", s.sampling_seconds},
          {"stage1_seconds", s.stage1_seconds},
          {"spp", s.spp},
          {"pass_a_spp", s.pass_a_spp},
          {"pass_b_spp", s.pass_b_spp},
          {"samples", s.samples},
          {"rays", s.rays},
          {"temporal_rays", s.temporal_rays},
          {"samples_per_second", s.samples_per_second},
          {"rays_per_second", s.rays_per_second},
          {"rel_mse", s.rel_mse},
          {"rel_mse_global", s.rel_mse_global},
          {"shift_failure_rate", s.shift_failure_rate},
          {"left_out", s.left_out}};
}

}  // namespace

std::string frame_entry_json(const WrittenFrame& frame) { return frame_json(frame).dump(); }

Expected<WrittenFrame> parse_frame_entry(const std::string& json_text) {
  auto j = nlohmann::json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return invalid_argument("a frame's statistics are not a JSON object");
  try {
    WrittenFrame r;
    r.file = j.value("file", std::string());
    r.bytes = j.value("bytes", uint64_t(0));
    FrameStats& s = r.stats;
    s.frame = j.value("frame", 0);
    s.render_seconds = j.value("render_seconds", 0.0);
    s.reconstruct_seconds = j.value("reconstruct_seconds", 0.0);
    s.feature_seconds = j.value("feature_seconds", 0.0);
    s.sampling_seconds = j.value("sampling_seconds", 0.0);
    s.stage1_seconds = j.value("stage1_seconds", 0.0);
    s.spp = j.value("spp", 0);
    s.pass_a_spp = j.value("pass_a_spp", 0);
    s.pass_b_spp = j.value("pass_b_spp", 0);
    s.samples = j.value("samples", uint64_t(0));
    s.rays = j.value("rays", uint64_t(0));
    s.temporal_rays = j.value("temporal_rays", uint64_t(0));
    s.samples_per_second = j.value("samples_per_second", 0.0);
    s.rays_per_second = j.value("rays_per_second", 0.0);
    s.rel_mse = j.value("rel_mse", -1.0);
    s.rel_mse_global = j.value("rel_mse_global", -1.0);
    s.shift_failure_rate = j.value("shift_failure_rate", -1.0);
    s.left_out = j.value("left_out", std::vector<std::string>());
    return r;
  } catch (const nlohmann::json::exception& e) {  // a field of the wrong type
    return invalid_argument(std::string("a frame's statistics: ") + e.what());
  }
}

std::string frame_file_name(int frame) { return numbered("frame_%04d.exr", frame); }

std::string stats_json(const std::vector<std::pair<std::string, std::string>>& header, int frames_total,
                       const std::vector<WrittenFrame>& frames) {
  nlohmann::ordered_json j;
  for (const auto& [k, v] : header) j[k] = v;
  j["frames_total"] = frames_total;
  j["frames_final"] = frames.size();
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  double render = 0, reconstruct = 0, features = 0;
  uint64_t rays = 0, temporal_rays = 0, samples = 0;
  std::map<std::string, int> left_out;  // how many frames left each thing out
  for (const WrittenFrame& r : frames) {
    list.push_back(frame_json(r));
    render += r.stats.render_seconds;
    reconstruct += r.stats.reconstruct_seconds;
    features += r.stats.feature_seconds;
    rays += r.stats.rays;
    temporal_rays += r.stats.temporal_rays;
    samples += r.stats.samples;
    for (const auto& l : r.stats.left_out) left_out[l]++;
  }
  j["frames"] = std::move(list);
  j["total"] = {{"render_seconds", render},
                {"reconstruct_seconds", reconstruct},
                {"feature_seconds", features},
                {"samples", samples},
                {"rays", rays},
                {"temporal_rays", temporal_rays},
                {"rays_per_second", render > 0 ? double(rays) / render : 0.0},
                {"left_out", left_out}};
  return j.dump(2) + "\n";
}

std::string preview_file_name(int frame) { return numbered("preview_%04d.png", frame); }

std::string video_file_name(const std::string& codec) {
  auto c = parse_video_codec(codec);
  if (!c.ok()) return "";
  return std::string("video.") + default_video_extension(*c);
}

std::string reference_path(const std::string& asset_root, const std::string& reference, int frame) {
  std::string name = reference;
  if (reference.find('%') != std::string::npos) {
    char buf[4096];
    // The pattern is validated to hold exactly one integer conversion.
    std::snprintf(buf, sizeof buf, reference.c_str(), frame);
    name = buf;
  }
  fs::path p = name;
  return p.is_absolute() ? name : (fs::path(asset_root) / p).string();
}

const Image* main_rgb(const LayeredImage& image) {
  if (const ImageLayer* l = image.find(""); l && l->image.channels() >= 3) return &l->image;
  for (const auto& l : image.layers)
    if (l.image.channels() >= 3) return &l.image;
  return nullptr;
}

void remove_stale_temporaries(const std::string& dir) {
  std::error_code ec;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    std::string name = it->path().filename().string();
    bool tmp = name.find(".tmp.") != std::string::npos ||
               (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0);
    if (tmp && it->is_regular_file()) fs::remove(it->path(), ec);
  }
}

const std::vector<std::string>& known_exr_layers() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n = {
        "direct",   "variance", "primal",   "dx",       "dy",       "dt",     "dxdt",
        "dydt",     "primal_var", "dx_var", "dy_var",   "dt_var",   "dxdt_var", "dydt_var",
        "shift_failure_rate", "temporal_failure_rate", "motion", "temporal_target"};
    // Every integrator's frames carry them (core/render/feature_buffers.h).
    n.insert(n.end(), feature_layer_names().begin(), feature_layer_names().end());
    return n;
  }();
  return names;
}

Status JobOutputs::validate(const JobSpec& job, const Options& options, int first_frame) {
  const std::string& ocio_config = options.ocio_config;
  const std::string& asset_root = options.asset_root;
  const auto& known = known_exr_layers();
  const auto& selected = job.outputs.exr_layers;
  for (size_t i = 0; i < selected.size(); ++i) {
    const std::string field = "outputs.exr_layers[" + std::to_string(i) + "]";
    if (std::find(known.begin(), known.end(), selected[i]) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      return invalid_argument(field + ": unknown layer '" + selected[i] + "' (known: " + list + ")");
    }
    if (std::find(selected.begin(), selected.begin() + long(i), selected[i]) != selected.begin() + long(i))
      return invalid_argument(field + ": layer '" + selected[i] + "' is listed twice");
  }
  if (wants_video(job)) GDVR_RETURN_IF_ERROR(with_field(parse_video_codec(job.outputs.video_codec).status(),
                                                       "outputs.video_codec"));
  if (wants_display(job)) {
    auto t = ColorTransform::create(transform_options(job, ocio_config));
    // Errors list the displays/views the config has; the field named is the
    // one a client can change.
    if (!t.ok()) return invalid_argument("outputs.ocio_display/ocio_view: " + t.status().message());
  }
  if (!job.reference.empty()) {
    const std::string& ref = job.reference;
    size_t pct = ref.find('%');
    if (pct != std::string::npos) {
      // Exactly one integer conversion ("%d", "%04d"): anything else would be
      // undefined behaviour in snprintf.
      size_t i = pct + 1;
      while (i < ref.size() && std::isdigit(static_cast<unsigned char>(ref[i]))) ++i;
      if (i >= ref.size() || ref[i] != 'd' || ref.find('%', i) != std::string::npos)
        return invalid_argument("reference: '" + ref + "' may hold one %d-style frame number pattern only");
    }
    std::string path = reference_path(asset_root, ref, first_frame);
    if (!is_inside_root(path, asset_root)) return invalid_argument("reference: '" + ref + "' is outside the asset root");
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return not_found("reference: '" + ref + "' does not exist");
    auto img = read_exr(path);
    if (!img.ok()) return invalid_argument("reference: '" + ref + "' is not a readable EXR: " + img.status().message());
    if (!main_rgb(*img)) return invalid_argument("reference: '" + ref + "' has no RGB layer");
  }
  return Status::Ok();
}

ExrCompression frame_exr_compression(const JobSpec& job) {
  // Under a time budget the write is paid out of the frame's time:
  // at 128x128, T-GPT's 56 channels cost 0.028 s over none as ZIP, 0.010 s as RLE
  // (docs/benchmarks.md, "EXR codecs").
  if (job.outputs.exr_compression == "auto") return job.time_budget_s > 0 ? ExrCompression::kRle : ExrCompression::kZip;
  auto c = parse_exr_compression(job.outputs.exr_compression);  // validated with the job
  return c.ok() ? *c : ExrCompression::kZip;
}

double JobOutputs::estimate_write_seconds(const LayeredImage& layers) const {
  const std::string probe = temporary_path_for(dir_ + "/time_budget_probe.exr");
  const auto start = std::chrono::steady_clock::now();
  const Status written = write_exr(probe, layers, /* half_float = */ false, frame_exr_compression(job_));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  discard_temporary(probe);
  return written.ok() ? seconds : 0.0;
}

Expected<std::unique_ptr<JobOutputs>> JobOutputs::open(const JobSpec& job, std::vector<int> frames, std::string dir,
                                                       Options options) {
  std::unique_ptr<JobOutputs> out(new JobOutputs());
  out->job_ = job;
  out->frames_ = std::move(frames);
  out->dir_ = std::move(dir);
  out->options_ = std::move(options);
  if (wants_display(job)) {
    auto t = ColorTransform::create(transform_options(job, out->options_.ocio_config));
    if (!t.ok()) return with_field(t.status(), "outputs.ocio_display/ocio_view");
    out->transform_ = std::make_unique<ColorTransform>(std::move(*t));
  }
  if (wants_video(job)) out->video_name_ = video_file_name(job.outputs.video_codec);
  if (!job.reference.empty() && job.reference.find('%') == std::string::npos) {
    auto ref = read_exr(reference_path(out->options_.asset_root, job.reference, 0));
    if (ref.ok() && main_rgb(*ref)) out->reference_ = std::make_unique<Image>(*main_rgb(*ref));
  }
  return Expected<std::unique_ptr<JobOutputs>>(std::move(out));
}

JobOutputs::~JobOutputs() = default;  // an unclosed encoder deletes its partial file

LayeredImage JobOutputs::selected_layers(const LayeredImage& image, std::vector<std::string>* left_out) const {
  const auto& selected = job_.outputs.exr_layers;
  LayeredImage kept;
  for (const ImageLayer& l : image.layers)
    if (l.name.empty() || std::find(selected.begin(), selected.end(), l.name) != selected.end()) kept.layers.push_back(l);
  for (const std::string& name : selected)
    if (!image.find(name))
      left_out->push_back("EXR layer '" + name + "': integrator " + integrator_name(job_.integrator) +
                          " does not produce it");
  return kept;
}

int64_t JobOutputs::video_frames() const { return video_ ? video_->frames_written() : 0; }

Expected<WrittenFrame> JobOutputs::write_frame(const FrameOutput& out) {
  const int frame = out.frame;
  WrittenFrame rec;
  rec.file = frame_file_name(frame);
  rec.stats = out.stats;
  rec.stats.frame = frame;
  const std::string path = dir_ + "/" + rec.file;
  const bool all_layers = job_.outputs.exr_layers.empty();
  const LayeredImage kept = all_layers ? LayeredImage() : selected_layers(out.image, &rec.stats.left_out);
  GDVR_RETURN_IF_ERROR(write_exr(path, all_layers ? out.image : kept, /* half_float = */ false, frame_exr_compression(job_))
                           .with_context("writing " + path + ": "));
  std::error_code ec;
  rec.bytes = uint64_t(fs::file_size(path, ec));
  const ImageLayer* failures = out.image.find("shift_failure_rate");
  rec.stats.shift_failure_rate = failures ? mean_finite(failures->image) : -1.0;

  const Image* rgb = main_rgb(out.image);
  if (!rgb) return internal_error("frame " + std::to_string(frame) + " has no RGB layer");
  if (transform_) {
    auto display = transform_->apply(*rgb);
    if (!display.ok()) return display.status();
    pending_display_ = std::move(*display);
    pending_frame_ = frame;
    if (job_.outputs.previews) {
      std::string png = dir_ + "/" + preview_file_name(frame);
      GDVR_RETURN_IF_ERROR(write_png8(png, pending_display_).with_context("writing " + png + ": "));
    }
  }
  rec.stats.rel_mse = rec.stats.rel_mse_global = -1;
  if (!job_.reference.empty()) {
    std::unique_ptr<Image> per_frame;
    const Image* ref = reference_.get();
    if (!ref) {
      auto img = read_exr(reference_path(options_.asset_root, job_.reference, frame));
      if (img.ok() && main_rgb(*img)) per_frame = std::make_unique<Image>(*main_rgb(*img));
      ref = per_frame.get();
    }
    if (!ref) {
      rec.stats.left_out.push_back("relMSE: no readable reference for frame " + std::to_string(frame));
    } else {
      auto sums = rel_mse_sums(*rgb, *ref);
      if (!sums.ok()) {
        rec.stats.left_out.push_back("relMSE: " + sums.status().message());
      } else {
        rec.stats.rel_mse = sums->per_pixel();
        rec.stats.rel_mse_global = sums->global();
      }
    }
  }
  return rec;
}

Expected<Image> JobOutputs::display_from_disk(int frame) {
  const std::string path = dir_ + "/" + frame_file_name(frame);
  auto img = read_exr(path);
  if (!img.ok()) return img.status();
  const Image* rgb = main_rgb(*img);
  if (!rgb) return internal_error(path + " has no RGB layer");
  return transform_->apply(*rgb);
}

Status JobOutputs::complete_earlier_frame(int frame) {
  if (!job_.outputs.previews || !transform_) return Status::Ok();
  const std::string png = dir_ + "/" + preview_file_name(frame);
  std::error_code ec;
  if (fs::exists(png, ec)) return Status::Ok();
  auto display = display_from_disk(frame);
  if (!display.ok()) return display.status().with_context("preview of frame " + std::to_string(frame) + ": ");
  return write_png8(png, *display).with_context("writing " + png + ": ");
}

Status JobOutputs::encode(const Image& display) {
  if (!video_) {
    VideoEncoderOptions o;
    auto codec = parse_video_codec(job_.outputs.video_codec);
    if (!codec.ok()) return codec.status();
    o.codec = *codec;
    o.width = display.width();
    o.height = display.height();
    fps_rational(job_.fps, &o.fps_num, &o.fps_den);
    auto enc = VideoEncoder::open(dir_ + "/" + video_name_, o);
    if (!enc.ok()) return enc.status();
    video_ = std::move(*enc);
  }
  return video_->add_frame(display);
}

Status JobOutputs::catch_up_before(int frame) {
  while (next_video_index_ < frames_.size() && frames_[next_video_index_] < frame) {
    const int f = frames_[next_video_index_];
    auto display = display_from_disk(f);
    if (!display.ok()) return display.status().with_context("video: re-encoding frame " + std::to_string(f) + ": ");
    GDVR_RETURN_IF_ERROR(encode(*display));
    ++next_video_index_;
  }
  return Status::Ok();
}

Status JobOutputs::add_to_video(int frame) {
  if (video_name_.empty()) return Status::Ok();
  GDVR_RETURN_IF_ERROR(catch_up_before(frame));
  if (next_video_index_ < frames_.size() && frames_[next_video_index_] == frame && pending_frame_ == frame) {
    GDVR_RETURN_IF_ERROR(encode(pending_display_));
    ++next_video_index_;
  }
  return Status::Ok();
}

Expected<std::string> JobOutputs::finish() {
  if (video_name_.empty()) return std::string();
  GDVR_RETURN_IF_ERROR(catch_up_before(INT32_MAX));
  if (!video_) return internal_error("video: no frame to encode");
  GDVR_RETURN_IF_ERROR(video_->close());
  return video_name_;
}

}  // namespace gdvr
