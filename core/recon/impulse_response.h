// How far one sample reaches in the L2 solve: the measurement behind the
// tiled solve's halo (docs/reconstruction.md, "Tiled solve"). The solve of a
// window whose primal is a unit impulse in the centre of its middle frame and
// whose gradients are all 0 is a multiple of a column of A⁻¹.
#pragma once

#include <vector>

#include "core/recon/recon_settings.h"
#include "core/util/status.h"

namespace gdvr {

// Per Chebyshev distance r = 0 … size/2 from the impulse, the largest
// |response| over every frame relative to the peak, for `frames` frames of
// size × size with all six terms, α and weights from `settings` (its method
// and tolerances are replaced: L2, CG to 1e-10).
Expected<std::vector<double>> impulse_response_by_distance(const ReconSettings& settings, int size, int frames);

}  // namespace gdvr
