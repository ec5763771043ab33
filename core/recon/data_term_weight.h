// How much the solve may trust a denoised data term, pixel by pixel.
//
// The screened Poisson objective weighs its data term by α against the
// sampled gradients. α = 0.2 suits the sampled primal, whose noise is far
// above the gradients'. A denoised primal D has little noise but a bias the
// denoiser cannot see (blurred edges, blotches at a few samples per pixel);
// how far to trust it depends on the scene: on a diffuse scene the gradients
// are sharp and D should only anchor the low frequencies, on a caustic or a
// near-specular surface the gradients are as noisy as the primal and D is
// the better estimate.
//
// The sampled gradients tell which case a pixel is in: they are unbiased,
// and T-GPT samples them in two independent passes, A and B. With
// r_A = ∇D − G_A and r_B = ∇D − G_B, the passes' noise is independent, so
// E[r_A·r_B] is the squared bias of D's gradients (D's own noise is small
// and shared by both), and E[(G_A − G_B)²]/4 the variance of the gradient
// estimate (G_A + G_B)/2. Both means are taken over a box of pixels, and
// the multiplier of α is
//
//   m = clamp( sqrt( variance / bias² ), 1, max_multiplier )
//
// α·m = α where D's detail is off by at least the gradients' noise (there the
// gradients decide, as with a sampled data term), up to α·max_multiplier where
// D agrees with the gradients to well within their noise. A negative or zero
// bias estimate, or no usable gradient nearby, gives max_multiplier.
//
// Measured on the four animations of docs/benchmarks.md: the variance layers
// of the estimate in place of the A/B difference trusted D less where the
// gradients are heavy-tailed (a caustic at 3 spp: 1.7e-2 against 1.3e-2
// per-pixel relMSE), a larger cap (50) or a gain on the ratio lost more on the
// diffuse scenes than they won on the stiff one, and blending the sampled
// primal back in where m is low did not win on either.
#pragma once

#include "core/image/image.h"
#include "core/util/status.h"

namespace gdvr {

struct DataTermWeightSettings {
  int radius = 4;                // box of (2r+1)² pixels for the local means
  double max_multiplier = 20.0;  // of α: 0.2 → 4 at most
};

// One-channel multipliers of α for data term `denoised` (RGB), from the
// spatial gradients of two independent passes (same shape as `denoised`).
// A constraint with a non-finite value in either pass is not used.
Expected<Image> data_term_weight(const Image& denoised, const Image& dx_a, const Image& dx_b, const Image& dy_a,
                                 const Image& dy_b, const DataTermWeightSettings& settings = {});

}  // namespace gdvr
