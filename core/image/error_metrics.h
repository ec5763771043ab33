// Error figures of a rendered image (sequence) against a reference
// (docs/report.md, "The figures"): both relMSE forms, temporal flicker, and helpers for
// equal-time comparisons on log-log curves.
#pragma once

#include <utility>
#include <vector>

#include "core/image/image.h"
#include "core/util/status.h"

namespace gdvr {

// Sums over the first three channels of every pixel; the forms average them
// as the survey and most papers do. Keeping the sums lets a sequence be
// combined exactly (global form over all frames).
struct RelMseSums {
  double squared_error = 0;      // Σ (I − I_ref)²
  double squared_reference = 0;  // Σ I_ref²
  double per_pixel_sum = 0;      // Σ (I − I_ref)² / (I_ref² + 0.01)
  double count = 0;              // number of channel values summed
  double non_finite = 0;         // values of I that were NaN/Inf (counted as error = reference)

  void add(const RelMseSums& o);
  // ‖I_ref − I‖² / ‖I_ref‖² (the survey's form); 0 for a black reference.
  double global() const { return squared_reference > 0 ? squared_error / squared_reference : 0.0; }
  // mean((I − I_ref)² / (I_ref² + 0.01)) (the papers' form).
  double per_pixel() const { return count > 0 ? per_pixel_sum / count : 0.0; }
};

// The offset ε = 0.01 of the per-pixel form.
constexpr double kRelMsePerPixelEpsilon = 0.01;

// Both images need >= 3 channels and the same size (the error names both sizes).
// A non-finite value of `image` counts as 0 (it is never hidden: `non_finite`
// counts it).
Expected<RelMseSums> rel_mse_sums(const Image& image, const Image& reference);

// Temporal flicker (docs/report.md): the mean over consecutive frame pairs of
// the mean squared change of the error e_t = I_t − R_t, i.e.
//   1/(T−1) Σ_t mean((e_{t+1} − e_t)²)   over the first three channels.
// A static error (bias) gives 0; independent noise of variance σ² gives 2σ².
// Needs >= 2 frames of equal sizes; kInvalidArgument otherwise.
Expected<double> temporal_flicker(const std::vector<const Image*>& images, const std::vector<const Image*>& references);

// Mean of the finite values of channel 0 (shift-failure rate maps); 0 if none.
double mean_finite(const Image& image);

// Value of a curve at x by linear interpolation of log y against log x between
// the two nearest points (points sorted by x internally; non-positive values
// ignored); an x equal to a point's x returns its y exactly. Beyond the ends
// the end segment extrapolates, up to a factor kLogLogExtrapolation in x
// (measured times scatter around their budget); further out, or with fewer
// than 2 points, NaN.
constexpr double kLogLogExtrapolation = 1.25;
double interpolate_log_log(std::vector<std::pair<double, double>> points, double x);

}  // namespace gdvr
