// Intel Open Image Denoise's `RT` filter (a CNN trained on path-traced
// images) on an HDR colour image, guided by albedo and normal images when
// given: the "path tracing + OIDN" baseline users compare gdvr with.
//
// OIDN is an optional dependency (docs/report.md, "Denoised baselines"). A
// build without it has this class all the same, but create() fails with a
// message that says how to get it; available() tells which build this is.
//
// Settings per call, as OIDN's docs recommend for final frames: hdr on
// (radiance, not display values), quality high, and cleanAux when the
// auxiliary images are noise-free (gdvr's feature buffers are: they are a
// fixed stratified average with glass split deterministically;
// core/render/feature_buffers.h). The device is OIDN's CPU device: the
// report times renderers on the CPU, and a denoise on a GPU would time
// another machine.
#pragma once

#include <memory>

#include "core/image/image.h"
#include "core/job/frame_denoiser.h"
#include "core/util/status.h"

namespace gdvr {

struct DenoiseInputs {
  const Image* color = nullptr;   // RGB radiance (3 channels)
  const Image* albedo = nullptr;  // optional RGB in [0, 1]
  const Image* normal = nullptr;  // optional world-space XYZ; OIDN takes it only with an albedo
  bool clean_aux = true;          // albedo and normal are noise-free (OIDN's cleanAux)
};

struct OidnDenoiserSettings {
  int threads = 0;  // the CPU device's numThreads; 0: OIDN chooses
  // The filter's maxMemoryMB: above it OIDN denoises the image in tiles.
  // 0: OIDN's default.
  int max_memory_mb = 0;
};

// What a job's denoiser may hold. A 2-frame 1080p T-GPT job's peak RSS
// (gdvr-render): 1.51 GB with the sampled data term, 3.11 GB with the
// denoised one at OIDN's default, 2.50 GB at 1024, 2.11 GB at 512 (and 256),
// for 10.8 / 10.4 / 12.1 s per frame; with the filter released after each
// 1080p call, 1.95 GB. A 24-frame 1080p server job: docs/benchmarks.md, "The
// service at 1080p".
inline constexpr int kJobDenoiserMaxMemoryMB = 512;

class OidnDenoiser {
 public:
  // Whether this build has OIDN (GDVR_HAVE_OIDN).
  static bool available();
  // kUnimplemented in a build without OIDN; kInternal when OIDN cannot make
  // a device (its message says why).
  static Expected<std::unique_ptr<OidnDenoiser>> create(const OidnDenoiserSettings& settings = {});
  ~OidnDenoiser();
  OidnDenoiser(const OidnDenoiser&) = delete;
  OidnDenoiser& operator=(const OidnDenoiser&) = delete;

  // The denoised colour. The filter is made once per image size and set of
  // inputs, and kept: OIDN's filters are costly to create, and a shot's
  // frames all look alike.
  Expected<Image> denoise(const DenoiseInputs& inputs);

 private:
  struct Impl;
  explicit OidnDenoiser(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A FrameDenoiser for jobs (core/job/frame_denoiser.h) on one OIDN device:
// calls from several jobs take turns (a filter is one image at a time).
FrameDenoiser oidn_frame_denoiser(std::shared_ptr<OidnDenoiser> denoiser);

// The FrameDenoiser a program passes its jobs: OIDN's when this build has it
// and a device can be made (with `threads` CPU threads, 0: OIDN chooses),
// none otherwise; *why says why there is none.
FrameDenoiser make_job_denoiser(int threads, std::string* why);

}  // namespace gdvr
