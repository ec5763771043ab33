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
  const size_t w = size_t(std::max(width, 0)), h = size_t(std::max(height, 0));
  if (weights.size() < w * h) return;  // empty
  std::vector<float> row_sums(h);
  rows_.reserve(w * h);
  for (size_t y = 0; y < h; ++y) row_sums[y] = float(build_alias_table(&weights[y * w], w, &rows_));
  if (!(build_alias_table(row_sums.data(), h, &marginal_) > 0)) {
    marginal_.clear();
    rows_.clear();
  }
}

Vec2f Distribution2D::sample(Vec2f u, float* pdf) const {
  const AliasSample y = sample_alias(marginal_.data(), marginal_.size(), u.y);
  const AliasSample x = sample_alias(&rows_[y.index * size_t(width_)], size_t(width_), u.x);
  *pdf = y.pmf * x.pmf * float(width_) * float(height_);
  return {(float(x.index) + x.u_remapped) / float(width_), (float(y.index) + y.u_remapped) / float(height_)};
}

Vec2f Distribution2D::prefetch_sample(Vec2f u) const {
  if (empty()) return {0.0f, 0.0f};
  const AliasSample y = sample_alias(marginal_.data(), marginal_.size(), u.y);
  const size_t x = std::min(size_t(width_) - 1, size_t(u.x * float(width_)));
  __builtin_prefetch(&rows_[y.index * size_t(width_) + x]);
  return {(float(x) + 0.5f) / float(width_), (float(y.index) + y.u_remapped) / float(height_)};
}

float Distribution2D::pdf(Vec2f p) const {
  if (empty()) return 0.0f;
  const size_t x = size_t(std::clamp(int(p.x * width_), 0, width_ - 1));
  const size_t y = size_t(std::clamp(int(p.y * height_), 0, height_ - 1));
  return marginal_[y].pmf * rows_[y * size_t(width_) + x].pmf * float(width_) * float(height_);
}

}  // namespace gdvr
