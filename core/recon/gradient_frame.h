// One frame's sampled buffers as the reconstruction sees them: the primal,
// the spatial gradients and (optionally) the temporal and mixed gradients
// towards the next frame, with optional per-pixel variances and validity masks.
//
// Conventions (docs/reconstruction.md): dx(p) ≈ I(p+e_x) − I(p), dy likewise,
// dt_t(p) ≈ I_{t+1}(p) − I_t(p), dxdt_t = dx_{t+1} − dx_t, dydt_t likewise.
// Constraints that would reach outside the image (dx in the last column, dy in
// the last row) or outside the window (temporal terms of its last frame) do not
// exist; whatever the buffers hold there is ignored.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/recon/term.h"
#include "core/util/status.h"

namespace gdvr {

struct GradientFrame {
  // Indexed by term_index(); an empty Image means "not sampled". The primal is
  // required; all non-empty buffers share width, height and channel count.
  std::array<Image, kTermCount> values;
  // Per-pixel variance of each buffer's estimate (same shape), empty if not
  // measured. Required by ReconMethod::kWeighted only.
  std::array<Image, kTermCount> variances;
  // Per-pixel validity (width*height bytes, nonzero = keep), empty = all valid.
  // The temporal sampler drops dt/dxdt/dydt where motion vectors fail (§4).
  std::array<std::vector<uint8_t>, kTermCount> valid;
  // Per-pixel multiplier of the primal term's weight α (one channel), empty =
  // 1 everywhere. A denoised data term gets one (core/recon/data_term_weight.h):
  // high where the denoised image agrees with the sampled gradients, 1 where
  // it does not.
  Image data_weight;
  // Where the temporal constraints of pixel p land in the next frame (two
  // channels X, Y of whole-pixel offsets o(p), +x right, +y down), empty = the
  // same pixel everywhere. With it the temporal terms follow the motion
  // (docs/reconstruction.md, "Motion-compensated temporal terms"):
  //   dt_t(p) ≈ I_{t+1}(p + o) − I_t(p),  dxdt_t(p) ≈ dx_{t+1}(p + o) − dx_t(p),
  //   dydt_t(p) ≈ dy_{t+1}(p + o) − dy_t(p).
  // A constraint whose target lies outside the image is dropped, and so is
  // every constraint after the first (in scan order) that lands on a pixel
  // another one of the frame already lands on.
  Image temporal_target;

  Image& buffer(Term t) { return values[term_index(t)]; }
  const Image& buffer(Term t) const { return values[term_index(t)]; }
  Image& variance(Term t) { return variances[term_index(t)]; }
  const Image& variance(Term t) const { return variances[term_index(t)]; }
  std::vector<uint8_t>& mask(Term t) { return valid[term_index(t)]; }
  const std::vector<uint8_t>& mask(Term t) const { return valid[term_index(t)]; }
  bool has(Term t) const { return !values[term_index(t)].empty(); }

  int width() const { return values[0].width(); }
  int height() const { return values[0].height(); }
  int channels() const { return values[0].channels(); }

  // Shapes agree, primal present, masks sized; names the offending buffer.
  Status validate() const;
};

// Builds a frame from film layers named "primal", "dx", "dy", "dt", "dxdt",
// "dydt" and variances "<name>_var" (missing layers stay empty).
Expected<GradientFrame> gradient_frame_from_layers(const LayeredImage& layers);

}  // namespace gdvr
