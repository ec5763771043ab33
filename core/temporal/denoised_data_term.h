// T-GPT's denoised data term (docs/tgpt.md, "The denoised data term"): the
// frame's primal, denoised with its feature buffers as guides, and a map of
// how far the window solve may trust it (core/recon/data_term_weight.h),
// both stored with the frame's stage-1 buffers so that a window, a tile of it
// or a farm's finalize reads them like any other layer.
#pragma once

#include "core/image/image.h"
#include "core/job/frame_denoiser.h"
#include "core/util/status.h"

namespace gdvr {

inline const char* const kDenoisedPrimalLayer = "data_denoised";  // RGB
inline const char* const kDataWeightLayer = "data_weight";         // Y: multiplier of α

// Adds the two layers to a T-GPT frame's stage-1 buffers, which must hold
// both passes' primal and spatial gradients and the feature buffers (albedo,
// N). Non-finite values in the denoiser's output are a failed denoise, not a
// data term.
Status add_denoised_data_term(const FrameDenoiser& denoise, LayeredImage* frame);

}  // namespace gdvr
