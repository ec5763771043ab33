#include "core/gradient/camera_hit_cache.h"

#include <algorithm>
#include <cassert>

namespace gdvr {

void CameraHitCache::begin(const Tile& tile, Vec2f jitter, PathCounters& counters) {
  x0_ = tile.x0 - 1;
  y0_ = tile.y0 - 1;
  width_ = tile.x1 - tile.x0 + 2;
  height_ = tile.y1 - tile.y0 + 2;
  jitter_ = jitter;
  const size_t n = size_t(width_) * size_t(height_);
  if (hits_.size() < n) hits_.resize(n);
  traced_.assign(n, 0);
  // The tile's own pixels, which every base path asks for, as streams of a
  // row at a time (Accelerator::intersect_stream: the same hits as single
  // casts, and camera rays are coherent).
  constexpr int kChunk = RayStreamBuffer::kCapacity;
  RayStreamBuffer rays;  // written and answered in place
  size_t entry[kChunk];  // index into hits_
  int m = 0;
  auto flush = [&] {
    scene_.accelerator().intersect_stream(rays, m, scene_.camera_geometry());
    counters.rays += uint64_t(m);
    for (int k = 0; k < m; ++k) {
      CameraHit& h = hits_[entry[k]];
      h.hit = rays.found(k);
      if (h.hit) scene_.interaction(h.ray, rays.hit(k), &h.si);
      traced_[entry[k]] = 1;
    }
    m = 0;
  };
  for (int y = tile.y0; y < tile.y1; ++y)
    for (int x = tile.x0; x < tile.x1; ++x) {
      entry[m] = size_t(y - y0_) * size_t(width_) + size_t(x - x0_);
      CameraHit& h = hits_[entry[m]];
      h.ray = camera_.generate_ray({float(x) + jitter_.x, float(y) + jitter_.y});
      set_stream_ray(rays, m, h.ray);
      if (++m == kChunk) flush();
    }
  if (m > 0) flush();
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
