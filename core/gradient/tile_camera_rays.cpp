#include "core/gradient/tile_camera_rays.h"

namespace gdvr {

void TileCameraRays::begin(const Tile& tile, int width, int height, const std::function<Vec2f(int x, int y)>& jitter,
                           bool offsets, PathCounters& counters) {
  tile_ = tile;
  const size_t n = size_t(tile.x1 - tile.x0) * size_t(tile.y1 - tile.y0);
  if (hits_.size() < n) hits_.resize(n);
  // Streams of up to kCapacity rays, answered in place
  // (Accelerator::intersect_stream: the same hits as single casts).
  constexpr int kChunk = RayStreamBuffer::kCapacity;
  RayStreamBuffer rays;
  CameraHit* entry[kChunk];
  int m = 0;
  const auto flush = [&] {
    scene_.accelerator().intersect_stream(rays, m, scene_.camera_geometry());
    counters.rays += uint64_t(m);
    for (int k = 0; k < m; ++k) {
      CameraHit& h = *entry[k];
      h.hit = rays.found(k);
      if (h.hit) scene_.interaction(h.ray, rays.hit(k), &h.si);
    }
    m = 0;
  };
  const auto add = [&](CameraHit* h, float fx, float fy) {
    h->ray = camera_.generate_ray({fx, fy});
    set_stream_ray(rays, m, h->ray);
    entry[m] = h;
    if (++m == kChunk) flush();
  };
  for (int y = tile.y0; y < tile.y1; ++y)
    for (int x = tile.x0; x < tile.x1; ++x) {
      const Vec2f j = jitter(x, y);
      auto& h = hits_[slot(x, y)];
      add(&h[0], float(x) + j.x, float(y) + j.y);
      if (!offsets) continue;
      for (int o = 0; o < kOffsetCount; ++o) {
        const int nx = x + kOffsetDx[size_t(o)], ny = y + kOffsetDy[size_t(o)];
        if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
        add(&h[size_t(1 + o)], float(nx) + j.x, float(ny) + j.y);
      }
    }
  if (m > 0) flush();
}

}  // namespace gdvr
