// A denoiser a program lends its jobs. core/job links none: the programs
// that have Intel Open Image Denoise (gdvr-render, gdvr-server, gdvr-farm,
// gdvr-report) wrap core/denoise's OidnDenoiser in one (make_job_denoiser,
// oidn_frame_denoiser) and pass it in JobRunOptions; T-GPT's denoised data
// term calls it once per frame.
#pragma once

#include <functional>

#include "core/image/image.h"
#include "core/util/status.h"

namespace gdvr {

// The denoised colour of an RGB radiance image, guided by the frame's albedo
// and shading normal (RGB, noise-free). May be called from several jobs'
// threads at once.
using FrameDenoiser = std::function<Expected<Image>(const Image& color, const Image& albedo, const Image& normal)>;

}  // namespace gdvr
