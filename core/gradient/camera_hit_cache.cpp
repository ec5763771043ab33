#include "core/gradient/camera_hit_cache.h"

#include <algorithm>
#include <cassert>

namespace gdvr {

void CameraHitCache::begin(const Tile& tile, Vec2f jitter) {
  x0_ = tile.x0 - 1;
  y0_ = tile.y0 - 1;
  width_ = tile.x1 - tile.x0 + 2;
  height_ = tile.y1 - tile.y0 + 2;
  jitter_ = jitter;
  const size_t n = size_t(width_) * size_t(height_);
  if (hits_.size() < n) hits_.resize(n);
  traced_.assign(n, 0);
}

const CameraHit& CameraHitCache::at(int x, int y, PathCounters& counters) {
  const int lx = x - x0_, ly = y - y0_;
  assert(lx >= 0 && ly >= 0 && lx < width_ && ly < height_);
  const size_t i = size_t(ly) * size_t(width_) + size_t(lx);
  if (!traced_[i]) {
    trace_camera_hit(scene_, camera_.generate_ray({float(x) + jitter_.x, float(y) + jitter_.y}), counters, &hits_[i]);
    traced_[i] = 1;
  }
  return hits_[i];
}

}  // namespace gdvr
