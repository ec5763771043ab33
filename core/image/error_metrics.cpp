#include "core/image/error_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace gdvr {
namespace {

std::string size_text(const Image& im) {
  return std::to_string(im.width()) + "x" + std::to_string(im.height()) + "x" + std::to_string(im.channels());
}

Status check_pair(const Image& image, const Image& reference) {
  if (image.channels() < 3 || reference.channels() < 3)
    return invalid_argument("relMSE: images need 3 channels (image " + size_text(image) + ", reference " +
                            size_text(reference) + ")");
  if (image.width() != reference.width() || image.height() != reference.height())
    return invalid_argument("relMSE: image is " + size_text(image) + " but the reference is " + size_text(reference));
  return Status::Ok();
}

}  // namespace

void RelMseSums::add(const RelMseSums& o) {
  squared_error += o.squared_error;
  squared_reference += o.squared_reference;
  per_pixel_sum += o.per_pixel_sum;
  count += o.count;
  non_finite += o.non_finite;
}

Expected<RelMseSums> rel_mse_sums(const Image& image, const Image& reference) {
  GDVR_RETURN_IF_ERROR(check_pair(image, reference));
  RelMseSums s;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        double v = image.at(x, y, c);
        double r = reference.at(x, y, c);
        if (!std::isfinite(r)) r = 0;  // a reference's own fireflies/NaN are not the image's fault
        if (!std::isfinite(v)) {
          v = 0;
          s.non_finite += 1;
        }
        const double d = v - r;
        s.squared_error += d * d;
        s.squared_reference += r * r;
        s.per_pixel_sum += d * d / (r * r + kRelMsePerPixelEpsilon);
        s.count += 1;
      }
  return s;
}

Expected<double> temporal_flicker(const std::vector<const Image*>& images, const std::vector<const Image*>& references) {
  if (images.size() != references.size())
    return invalid_argument("flicker: " + std::to_string(images.size()) + " frames but " +
                            std::to_string(references.size()) + " reference frames");
  if (images.size() < 2) return invalid_argument("flicker: needs at least 2 frames");
  for (size_t t = 0; t < images.size(); ++t) {
    GDVR_RETURN_IF_ERROR(check_pair(*images[t], *references[t]).with_context("frame " + std::to_string(t) + ": "));
    GDVR_RETURN_IF_ERROR(check_pair(*images[t], *images[0]).with_context("frame " + std::to_string(t) + ": "));
  }
  auto err = [](const Image& im, const Image& ref, int x, int y, int c) {
    double v = im.at(x, y, c), r = ref.at(x, y, c);
    if (!std::isfinite(v)) v = 0;
    if (!std::isfinite(r)) r = 0;
    return v - r;
  };
  double total = 0;
  for (size_t t = 0; t + 1 < images.size(); ++t) {
    const Image &a = *images[t], &b = *images[t + 1], &ra = *references[t], &rb = *references[t + 1];
    double s = 0;
    for (int y = 0; y < a.height(); ++y)
      for (int x = 0; x < a.width(); ++x)
        for (int c = 0; c < 3; ++c) {
          const double d = err(b, rb, x, y, c) - err(a, ra, x, y, c);
          s += d * d;
        }
    total += s / (3.0 * double(a.pixel_count()));
  }
  return total / double(images.size() - 1);
}

double mean_finite(const Image& image) {
  if (image.channels() < 1) return 0;
  double sum = 0;
  size_t n = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      const float v = image.at(x, y, 0);
      if (std::isfinite(v)) {
        sum += v;
        ++n;
      }
    }
  return n ? sum / double(n) : 0.0;
}

double interpolate_log_log(std::vector<std::pair<double, double>> points, double x) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  points.erase(std::remove_if(points.begin(), points.end(),
                              [](const auto& p) {
                                return !(p.first > 0) || !(p.second > 0) || !std::isfinite(p.first) ||
                                       !std::isfinite(p.second);
                              }),
               points.end());
  if (points.empty() || !(x > 0)) return nan;
  std::sort(points.begin(), points.end());
  for (const auto& p : points)
    if (p.first == x) return p.second;
  if (points.size() < 2 || x < points.front().first / kLogLogExtrapolation ||
      x > points.back().first * kLogLogExtrapolation)
    return nan;
  // The segment around x, or the end segment for a short extrapolation.
  size_t i = 0;
  while (i + 2 < points.size() && x > points[i + 1].first) ++i;
  const auto &a = points[i], &b = points[i + 1];
  if (a.first == b.first) return nan;
  const double t = (std::log(x) - std::log(a.first)) / (std::log(b.first) - std::log(a.first));
  return std::exp(std::log(a.second) + t * (std::log(b.second) - std::log(a.second)));
}

}  // namespace gdvr
