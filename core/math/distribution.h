// Discrete and piecewise-constant distributions for importance sampling
// (emitter selection by area, environment maps by luminance).
#pragma once

#include <cstdint>
#include <vector>

#include "core/math/alias_table.h"
#include "core/math/vec.h"

namespace gdvr {

class Distribution1D {
 public:
  Distribution1D() = default;
  // Non-negative weights; an all-zero or empty input yields an empty distribution.
  explicit Distribution1D(std::vector<float> weights);

  bool empty() const { return cdf_.empty() || total_ <= 0; }
  size_t size() const { return weights_.size(); }
  double total() const { return total_; }
  float pmf(size_t i) const { return pmf_[i]; }
  // Samples an index; `u_remapped` (optional) receives u rescaled to [0,1) within the bin.
  size_t sample(float u, float* u_remapped = nullptr) const;

 private:
  std::vector<double> weights_, cdf_;  // double: long lists of tiny triangles
  std::vector<float> pmf_;             // weights_ / total_, precomputed (no division per sample)
  // Cutpoints (Chen & Asau 1974): guide_[k] is the first bin whose cdf exceeds
  // k/G of the total, so a sample starts its search there and moves a step or
  // two, instead of a binary search over the whole cdf (a 1024-column
  // environment map row: 10 dependent, cache-missing steps).
  std::vector<uint32_t> guide_;
  double total_ = 0;
  bool uniform_ = false;  // all weights equal: sample() needs no search
};

// Piecewise-constant 2D distribution on [0,1]^2 from a width x height grid,
// sampled through alias tables (alias_table.h): a marginal over rows and one
// table per row, flattened so that row y's slots start at y * width.
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(const std::vector<float>& weights, int width, int height);

  bool empty() const { return marginal_.empty(); }
  // Returns a point in [0,1)^2 and its density w.r.t. area in [0,1]^2.
  Vec2f sample(Vec2f u, float* pdf) const;
  float pdf(Vec2f p) const;
  // Prefetches the row slot sample(u) reads and returns the point sample(u)
  // returns when that slot keeps its own bin (up to where in the bin), for a
  // caller that prefetches data at the point. Reads only the marginal, which
  // is small enough to stay cached.
  Vec2f prefetch_sample(Vec2f u) const;

  // The alias tables sample() reads (for a vector kernel that repeats it):
  // the marginal's height() slots, then width() slots per row.
  int width() const { return width_; }
  int height() const { return height_; }
  const AliasSlot* marginal_slots() const { return marginal_.data(); }
  const AliasSlot* row_slots() const { return rows_.data(); }

 private:
  int width_ = 0, height_ = 0;
  std::vector<AliasSlot> marginal_;  // empty when no weight is positive
  std::vector<AliasSlot> rows_;
};

}  // namespace gdvr
