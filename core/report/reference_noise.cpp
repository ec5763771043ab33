#include "core/report/reference_noise.h"

#include <cmath>
#include <string>

#include "core/image/error_metrics.h"

namespace gdvr {

Expected<ReferenceNoiseFloor> reference_noise_floor(const std::vector<const Image*>& references,
                                                    const std::vector<const Image*>& variances) {
  if (references.empty()) return invalid_argument("reference noise: no frames");
  if (references.size() != variances.size())
    return invalid_argument("reference noise: " + std::to_string(references.size()) + " frames but " +
                            std::to_string(variances.size()) + " variance images");
  const Image& first = *references.front();
  double var_sum = 0, ref_sq = 0, per_pixel_sum = 0, count = 0;
  std::vector<double> frame_mean_var;  // mean variance per value, per frame
  for (size_t i = 0; i < references.size(); ++i) {
    const Image& r = *references[i];
    const Image& v = *variances[i];
    if (r.width() != first.width() || r.height() != first.height() || r.channels() < 3)
      return invalid_argument("reference noise: frame " + std::to_string(i) + " differs in size or has < 3 channels");
    if (v.width() != r.width() || v.height() != r.height() || v.channels() < 3)
      return invalid_argument("reference noise: the variance of frame " + std::to_string(i) +
                              " does not match its reference (" + std::to_string(v.width()) + "x" +
                              std::to_string(v.height()) + "x" + std::to_string(v.channels()) + ")");
    double frame_var = 0;
    for (int y = 0; y < r.height(); ++y)
      for (int x = 0; x < r.width(); ++x)
        for (int c = 0; c < 3; ++c) {
          const double rv = std::isfinite(r.at(x, y, c)) ? r.at(x, y, c) : 0.0;
          const double var = std::isfinite(v.at(x, y, c)) ? std::max(0.0f, v.at(x, y, c)) : 0.0;
          var_sum += var;
          frame_var += var;
          ref_sq += rv * rv;
          per_pixel_sum += var / (rv * rv + kRelMsePerPixelEpsilon);
          count += 1;
        }
    frame_mean_var.push_back(frame_var / (3.0 * double(r.pixel_count())));
  }
  ReferenceNoiseFloor floor;
  floor.global = ref_sq > 0 ? var_sum / ref_sq : 0.0;
  floor.per_pixel = per_pixel_sum / count;
  if (frame_mean_var.size() >= 2) {
    double s = 0;
    for (size_t t = 0; t + 1 < frame_mean_var.size(); ++t) s += frame_mean_var[t] + frame_mean_var[t + 1];
    floor.flicker = s / double(frame_mean_var.size() - 1);
  }
  return floor;
}

}  // namespace gdvr
