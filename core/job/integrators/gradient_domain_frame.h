// What the gradient-domain runners (G-PT and T-GPT) share: the reconstruction
// settings a job asks for, the direct light added after the solve, and the
// notes their frames carry.
#pragma once

#include <cstdint>

#include "core/gradient/gpt_settings.h"
#include "core/image/image.h"
#include "core/job/frame_output.h"
#include "core/job/job_spec.h"
#include "core/recon/recon_settings.h"
#include "core/scene/scene.h"

namespace gdvr {

// `base` with the job's method, alpha and term weights.
ReconSettings job_recon_settings(const ReconstructionSpec& spec, ReconSettings base);

// Adds the light seen directly from the camera to the solved image. The solve
// drops non-finite samples; `direct` bypasses it, so they are dropped here too
// (a corrupted farm file must not put NaN into the final image). Returns how
// many values were dropped.
//
// With `clamp`, the sum is clamped at 0: a least-squares solve rings around an
// outlier gradient (a glossy firefly) with negative lobes, and negative
// radiance is never the answer, so the clamp moves every such pixel closer to
// any reference (veach-mis, G-PT L2 at 32 spp: 8921 negative values, per-pixel
// relMSE 1.65 -> 0.87; docs/reconstruction.md). It makes the estimate
// consistent rather than unbiased (the mean of dark pixels rises), so jobs
// can turn it off (reconstruction.clamp_negative).
int64_t add_direct_clamped(const Image& direct, bool clamp, Image* final_image);

// The stage-1 layers go into the output as they came, except values that are
// not finite (only a corrupted buffer file has them): zeroed and counted.
void zero_non_finite_layers(FrameOutput* out);

// A scene without glossy or specular BSDFs never runs the shifts' glossy
// machinery (half-vector copy): said in left_out, unless the shift is replay.
void note_unused_glossy_shift(const Scene& scene, const GptSettings& gpt, FrameStats* stats);

}  // namespace gdvr
