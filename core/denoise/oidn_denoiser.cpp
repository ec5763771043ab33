#include "core/denoise/oidn_denoiser.h"

#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#ifdef GDVR_HAVE_OIDN
#include "core/denoise/oidn_api.h"
#endif

namespace gdvr {
namespace {

Status check_inputs(const DenoiseInputs& in) {
  if (!in.color || in.color->empty()) return invalid_argument("denoise: no colour image");
  const int w = in.color->width(), h = in.color->height();
  auto check = [&](const Image* im, const char* name) -> Status {
    if (!im) return Status::Ok();
    if (im->channels() != 3) return invalid_argument(std::string("denoise: the ") + name + " image needs 3 channels");
    if (im->width() != w || im->height() != h)
      return invalid_argument(std::string("denoise: the ") + name + " image is not the colour image's size");
    return Status::Ok();
  };
  GDVR_RETURN_IF_ERROR(check(in.color, "colour"));
  GDVR_RETURN_IF_ERROR(check(in.albedo, "albedo"));
  GDVR_RETURN_IF_ERROR(check(in.normal, "normal"));
  if (in.normal && !in.albedo) return invalid_argument("denoise: OIDN takes a normal image only with an albedo image");
  return Status::Ok();
}

}  // namespace

#ifdef GDVR_HAVE_OIDN

// A filter for images up to this many pixels is kept for the next call (its
// set-up costs about what a small image's denoise does); a larger one is
// released after each, so that its scratch memory (hundreds of MB at 1080p)
// is not held while a job does other work, such as T-GPT's window solves.
constexpr size_t kKeepFilterPixels = size_t(1) << 20;

struct OidnDenoiser::Impl {
  OIDNDevice device = nullptr;
  OIDNFilter filter = nullptr;
  int max_memory_mb = 0;
  // What `filter` was set up for, and the images it reads and writes.
  int width = 0, height = 0;
  bool with_albedo = false, with_normal = false, clean_aux = false;
  std::vector<float> color, albedo, normal, output;

  ~Impl() {
    release_filter();
    if (device) oidnReleaseDevice(device);
  }

  // The filter and its images, with the scratch memory OIDN keeps for them.
  void release_filter() {
    if (filter) oidnReleaseFilter(filter);
    filter = nullptr;
    width = height = 0;
    for (std::vector<float>* v : {&color, &albedo, &normal, &output}) std::vector<float>().swap(*v);
  }

  // The device's first error since the last call, if any.
  Status device_error(const std::string& during) const {
    const char* message = nullptr;
    if (oidnGetDeviceError(device, &message) == OIDN_ERROR_NONE) return Status::Ok();
    return internal_error("OIDN: " + during + ": " + (message ? message : "unknown error"));
  }

  Status set_up_filter(const DenoiseInputs& in) {
    const int w = in.color->width(), h = in.color->height();
    const bool a = in.albedo != nullptr, n = in.normal != nullptr;
    const bool clean = (a || n) && in.clean_aux;
    if (filter && w == width && h == height && a == with_albedo && n == with_normal && clean == clean_aux)
      return Status::Ok();
    if (filter) oidnReleaseFilter(filter);
    filter = oidnNewFilter(device, "RT");
    if (!filter) return device_error("creating the RT filter");
    width = w, height = h, with_albedo = a, with_normal = n, clean_aux = clean;
    const size_t floats = size_t(w) * size_t(h) * 3;
    color.assign(floats, 0.0f);
    output.assign(floats, 0.0f);
    albedo.assign(a ? floats : 0, 0.0f);
    normal.assign(n ? floats : 0, 0.0f);
    auto share = [&](const char* name, std::vector<float>& pixels) {
      oidnSetSharedFilterImage(filter, name, pixels.data(), OIDN_FORMAT_FLOAT3, size_t(w), size_t(h), 0, 0, 0);
    };
    share("color", color);
    if (a) share("albedo", albedo);
    if (n) share("normal", normal);
    share("output", output);
    oidnSetFilterBool(filter, "hdr", true);
    oidnSetFilterInt(filter, "quality", OIDN_QUALITY_HIGH);
    if (max_memory_mb > 0) oidnSetFilterInt(filter, "maxMemoryMB", max_memory_mb);
    oidnSetFilterBool(filter, "cleanAux", clean);
    oidnCommitFilter(filter);
    Status st = device_error("setting up the RT filter");
    if (!st.ok()) {
      oidnReleaseFilter(filter);
      filter = nullptr;
    }
    return st;
  }
};

namespace {

// OIDN spreads a NaN over its whole receptive field; a sample the renderer
// could not finish is black in the image, and black here.
void copy_finite(const Image& from, std::vector<float>* to) {
  const std::vector<float>& d = from.data();
  for (size_t k = 0; k < d.size(); ++k) (*to)[k] = std::isfinite(d[k]) ? d[k] : 0.0f;
}

}  // namespace

bool OidnDenoiser::available() { return true; }

Expected<std::unique_ptr<OidnDenoiser>> OidnDenoiser::create(const OidnDenoiserSettings& settings) {
  auto impl = std::make_unique<Impl>();
  impl->max_memory_mb = settings.max_memory_mb;
  impl->device = oidnNewDevice(OIDN_DEVICE_TYPE_CPU);
  if (!impl->device) {
    const char* message = nullptr;
    oidnGetDeviceError(nullptr, &message);  // a failed creation reports on the null device
    return internal_error(std::string("OIDN: no CPU device: ") + (message ? message : "unknown error"));
  }
  if (settings.threads > 0) oidnSetDeviceInt(impl->device, "numThreads", settings.threads);
  // OIDN's CPU device runs on the process's TBB, the one gdvr renders with,
  // and would pin the worker threads that enter its arena to cores; OIDN's
  // docs advise turning that off where the application shares the threads.
  oidnSetDeviceBool(impl->device, "setAffinity", false);
  oidnCommitDevice(impl->device);
  GDVR_RETURN_IF_ERROR(impl->device_error("creating the CPU device"));
  return std::unique_ptr<OidnDenoiser>(new OidnDenoiser(std::move(impl)));
}

Expected<Image> OidnDenoiser::denoise(const DenoiseInputs& in) {
  GDVR_RETURN_IF_ERROR(check_inputs(in));
  GDVR_RETURN_IF_ERROR(impl_->set_up_filter(in));
  copy_finite(*in.color, &impl_->color);
  if (in.albedo) copy_finite(*in.albedo, &impl_->albedo);
  if (in.normal) copy_finite(*in.normal, &impl_->normal);
  oidnExecuteFilter(impl_->filter);
  GDVR_RETURN_IF_ERROR(impl_->device_error("denoising"));
  Image out(impl_->width, impl_->height, 3);
  out.data() = impl_->output;
  if (size_t(impl_->width) * size_t(impl_->height) > kKeepFilterPixels) impl_->release_filter();
  return out;
}

#else  // built without OIDN

struct OidnDenoiser::Impl {};

namespace {

Status built_without_oidn() {
  return unimplemented(
      "denoise: gdvr was built without Intel Open Image Denoise (OIDN). Install it with deploy/install-deps.sh "
      "(a venv at /opt/gdvr/oidn-venv) and configure the build again; CMake's GDVR_OIDN_VENV or "
      "OpenImageDenoise_DIR point it at another copy");
}

}  // namespace

bool OidnDenoiser::available() { return false; }

Expected<std::unique_ptr<OidnDenoiser>> OidnDenoiser::create(const OidnDenoiserSettings&) {
  return built_without_oidn();
}

Expected<Image> OidnDenoiser::denoise(const DenoiseInputs& in) {
  GDVR_RETURN_IF_ERROR(check_inputs(in));
  return built_without_oidn();
}

#endif

OidnDenoiser::OidnDenoiser(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OidnDenoiser::~OidnDenoiser() = default;

FrameDenoiser oidn_frame_denoiser(std::shared_ptr<OidnDenoiser> denoiser) {
  auto turn = std::make_shared<std::mutex>();
  return [denoiser = std::move(denoiser), turn](const Image& color, const Image& albedo,
                                                 const Image& normal) -> Expected<Image> {
    DenoiseInputs in;
    in.color = &color;
    in.albedo = &albedo;
    in.normal = &normal;
    std::lock_guard<std::mutex> lock(*turn);
    return denoiser->denoise(in);
  };
}

FrameDenoiser make_job_denoiser(int threads, std::string* why) {
  OidnDenoiserSettings settings;
  settings.threads = threads;
  settings.max_memory_mb = kJobDenoiserMaxMemoryMB;
  auto d = OidnDenoiser::create(settings);
  if (!d.ok()) {
    if (why) *why = d.status().message();
    return {};
  }
  return oidn_frame_denoiser(std::shared_ptr<OidnDenoiser>(std::move(d.value())));
}

}  // namespace gdvr
