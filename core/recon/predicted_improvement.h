// Frequency-domain prediction of what the L2 reconstruction buys
// (the frequency analysis of Kettunen et al. 2015; docs/reconstruction.md,
// "Predicted improvement"). For stationary white noise of variance σ_p² in the primal
// and σ_c² in each gradient buffer, the screened Poisson solve has, per
// frequency ω, the error variance
//   e(ω) = (a² σ_p² + Σ_c w_c² |D_c(ω)|² σ_c²) / (a + Σ_c w_c |D_c(ω)|²)²,   a = α² w_primal,
// with |D(ω)|² = 4 sin²(ω/2) per axis and products of them for the mixed
// terms. Averaging e(ω) over the frequency cube and dividing σ_p² by it gives
// the predicted error-reduction factor versus the primal alone.
#pragma once

#include <array>

#include "core/recon/gradient_window.h"
#include "core/recon/recon_settings.h"

namespace gdvr {

// Mean per-pixel variance of each buffer (0 = noise-free or absent).
struct NoiseLevels {
  std::array<double, kTermCount> variance{};
  double& operator[](Term t) { return variance[term_index(t)]; }
  double operator[](Term t) const { return variance[term_index(t)]; }
};

// Predicted MSE of the L2 result (in the units of the variances). `temporal`
// integrates over the time frequency too (a long sequence; the window's
// borders are ignored). Uses settings.alpha and settings.term_weights.
double predicted_l2_error_variance(const NoiseLevels& noise, const ReconSettings& settings, bool temporal);

// σ_p² / predicted MSE: > 1 means the reconstruction is expected to beat the
// primal by that factor. Needs noise[kPrimal] > 0.
Expected<double> predicted_improvement(const NoiseLevels& noise, const ReconSettings& settings, bool temporal);

// Averages the variance buffers of a window over finite entries, all
// channels and frames; kInvalidArgument if the primal has no variance.
Expected<NoiseLevels> measure_noise_levels(const GradientWindow& window);

}  // namespace gdvr
