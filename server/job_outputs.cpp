#include "server/job_outputs.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>

#include "core/io/image_io.h"
#include "core/report/error_metrics.h"
#include "core/util/path_confinement.h"

namespace gdvr::server {
namespace fs = std::filesystem;

namespace {

bool wants_video(const JobSpec& job) { return job.outputs.video_codec != "none"; }
bool wants_display(const JobSpec& job) { return job.outputs.previews || wants_video(job); }

ColorTransformOptions transform_options(const JobSpec& job, const std::string& ocio_config) {
  ColorTransformOptions o;
  o.config_path = resolve_ocio_config_path(ocio_config);
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

}  // namespace

std::string preview_file_name(int frame) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "preview_%04d.png", frame);
  return buf;
}

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

Status JobOutputs::validate(const JobSpec& job, const std::string& ocio_config, const std::string& asset_root,
                            int first_frame) {
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

Expected<std::unique_ptr<JobOutputs>> JobOutputs::open(const JobSpec& job, std::vector<int> frames, std::string dir,
                                                       const std::string& ocio_config, std::string asset_root) {
  std::unique_ptr<JobOutputs> out(new JobOutputs());
  out->job_ = job;
  out->frames_ = std::move(frames);
  out->dir_ = std::move(dir);
  out->asset_root_ = std::move(asset_root);
  if (wants_display(job)) {
    auto t = ColorTransform::create(transform_options(job, ocio_config));
    if (!t.ok()) return with_field(t.status(), "outputs.ocio_display/ocio_view");
    out->transform_ = std::make_unique<ColorTransform>(std::move(*t));
  }
  if (wants_video(job)) out->video_name_ = video_file_name(job.outputs.video_codec);
  if (!job.reference.empty() && job.reference.find('%') == std::string::npos) {
    auto ref = read_exr(reference_path(out->asset_root_, job.reference, 0));
    if (ref.ok() && main_rgb(*ref)) out->reference_ = std::make_unique<Image>(*main_rgb(*ref));
  }
  return Expected<std::unique_ptr<JobOutputs>>(std::move(out));
}

JobOutputs::~JobOutputs() = default;  // an unclosed encoder deletes its partial file

int64_t JobOutputs::video_frames() const { return video_ ? video_->frames_written() : 0; }

Status JobOutputs::prepare_frame(int frame, const LayeredImage& image, FrameErrors* errors,
                                 std::vector<std::string>* left_out) {
  *errors = FrameErrors{};
  const Image* rgb = main_rgb(image);
  if (!rgb) return internal_error("frame " + std::to_string(frame) + " has no RGB layer");
  if (transform_) {
    auto display = transform_->apply(*rgb);
    if (!display.ok()) return display.status();
    pending_display_ = std::move(*display);
    pending_frame_ = frame;
    if (job_.outputs.previews) {
      std::string path = dir_ + "/" + preview_file_name(frame);
      GDVR_RETURN_IF_ERROR(write_png8(path, pending_display_).with_context("writing " + path + ": "));
    }
  }
  if (!job_.reference.empty()) {
    std::unique_ptr<Image> per_frame;
    const Image* ref = reference_.get();
    if (!ref) {
      auto img = read_exr(reference_path(asset_root_, job_.reference, frame));
      if (img.ok() && main_rgb(*img)) per_frame = std::make_unique<Image>(*main_rgb(*img));
      ref = per_frame.get();
    }
    if (!ref) {
      left_out->push_back("relMSE: no readable reference for frame " + std::to_string(frame));
    } else {
      auto sums = rel_mse_sums(*rgb, *ref);
      if (!sums.ok()) {
        left_out->push_back("relMSE: " + sums.status().message());
      } else {
        errors->rel_mse = sums->per_pixel();
        errors->rel_mse_global = sums->global();
      }
    }
  }
  return Status::Ok();
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
    int f = frames_[next_video_index_];
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.exr", f);
    std::string path = dir_ + "/" + name;
    auto img = read_exr(path);
    if (!img.ok()) return img.status().with_context("video: re-encoding frame " + std::to_string(f) + ": ");
    const Image* rgb = main_rgb(*img);
    if (!rgb) return internal_error("video: " + path + " has no RGB layer");
    auto display = transform_->apply(*rgb);
    if (!display.ok()) return display.status();
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

}  // namespace gdvr::server
