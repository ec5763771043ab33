// Reconstruction entry point: a pure function from a window of sampled
// buffers to images (the reconstructor knows nothing of the renderer: docs/architecture.md).
#pragma once

#include "core/image/pixel_rect.h"
#include "core/recon/gradient_window.h"
#include "core/recon/recon_result.h"
#include "core/recon/recon_settings.h"

namespace gdvr {

// Solves the objective of docs/reconstruction.md over all frames of the window with
// settings.method. Invalid settings or buffers give kInvalidArgument; NaN/Inf
// samples are dropped (counted in stats), never propagated to the output.
Expected<ReconResult> reconstruct(const GradientWindow& window, const ReconSettings& settings);
// Same, with the stats' dropped-constraint counts limited to the pixels of
// `counted` (a tile's core in the tile's coordinates: tiled_reconstruct.h).
Expected<ReconResult> reconstruct(const GradientWindow& window, const ReconSettings& settings,
                                  const PixelRect& counted);

// One frame, spatial terms only (W = 1).
Expected<ReconResult> reconstruct_frame(const GradientFrame& frame, const ReconSettings& settings);

}  // namespace gdvr
