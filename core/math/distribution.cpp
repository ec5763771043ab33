#include "core/math/distribution.h"

#include <algorithm>
#include <cmath>

namespace gdvr {

Distribution1D::Distribution1D(std::vector<float> weights) {
  weights_.resize(weights.size());
  cdf_.resize(weights.size());
  double sum = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    double w = (std::isfinite(weights[i]) && weights[i] > 0) ? double(weights[i]) : 0.0;
    weights_[i] = w;
    sum += w;
    cdf_[i] = sum;
  }
  total_ = sum;
  if (!(total_ > 0)) {
    cdf_.clear();
    return;
  }
  uniform_ = std::all_of(weights_.begin(), weights_.end(), [&](double w) { return w == weights_[0]; });
  pmf_.resize(weights_.size());
  for (size_t k = 0; k < weights_.size(); ++k) pmf_[k] = float(weights_[k] / total_);
  const size_t g = cdf_.size();
  guide_.resize(g);
  size_t i = 0;
  for (size_t k = 0; k < g; ++k) {
    const double threshold = total_ * (double(k) / double(g));
    while (i + 1 < cdf_.size() && cdf_[i] <= threshold) ++i;
    guide_[k] = uint32_t(i);
  }
}

size_t Distribution1D::sample(float u, float* u_remapped) const {
  if (cdf_.empty()) {  // no positive weight: callers check empty(); stay in bounds anyway
    if (u_remapped) *u_remapped = u;
    return 0;
  }
  const size_t n = cdf_.size();
  if (uniform_) {
    // Equal weights (a quad light's two triangles): the bin is floor(u n), with
    // no data-dependent search whose branches a random u mispredicts.
    const double scaled = double(u) * double(n);
    const size_t i = std::min(n - 1, size_t(scaled));
    if (u_remapped) *u_remapped = float(std::clamp(scaled - double(i), 0.0, double(0x1.fffffep-1f)));
    return i;
  }
  const double target = double(u) * total_;
  // The first bin whose cdf exceeds target (upper_bound), found from the
  // cutpoint; the backward step keeps it exact whatever the rounding of
  // target against the cutpoint thresholds.
  size_t i = guide_[std::min(n - 1, size_t(double(u) * double(n)))];
  while (i > 0 && cdf_[i - 1] > target) --i;
  while (i + 1 < n && cdf_[i] <= target) ++i;
  while (weights_[i] == 0 && i > 0) --i;  // never land on a zero-weight bin
  if (u_remapped) {
    double lo = i > 0 ? cdf_[i - 1] : 0.0;
    double r = weights_[i] > 0 ? (target - lo) / weights_[i] : 0.0;
    *u_remapped = float(std::clamp(r, 0.0, double(0x1.fffffep-1f)));
  }
  return i;
}

Distribution2D::Distribution2D(const std::vector<float>& weights, int width, int height)
    : width_(width), height_(height) {
  std::vector<float> row_sums(height);
  conditional_.reserve(height);
  for (int y = 0; y < height; ++y) {
    std::vector<float> row(weights.begin() + size_t(y) * width, weights.begin() + size_t(y + 1) * width);
    conditional_.emplace_back(row);
    row_sums[y] = float(conditional_.back().total());
  }
  marginal_ = Distribution1D(row_sums);
  if (marginal_.empty()) conditional_.clear();
}

Vec2f Distribution2D::sample(Vec2f u, float* pdf) const {
  float uy, ux;
  size_t y = marginal_.sample(u.y, &uy);
  size_t x = conditional_[y].sample(u.x, &ux);
  *pdf = marginal_.pmf(y) * conditional_[y].pmf(x) * float(width_) * float(height_);
  return {(float(x) + ux) / float(width_), (float(y) + uy) / float(height_)};
}

float Distribution2D::pdf(Vec2f p) const {
  if (empty()) return 0.0f;
  int x = std::clamp(int(p.x * width_), 0, width_ - 1);
  int y = std::clamp(int(p.y * height_), 0, height_ - 1);
  if (conditional_[y].empty()) return 0.0f;
  return marginal_.pmf(y) * conditional_[y].pmf(x) * float(width_) * float(height_);
}

}  // namespace gdvr
