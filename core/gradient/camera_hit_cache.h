// First hits of one sample index's camera rays over a tile and the ring of
// pixels around it, for G-PT with a shared sub-pixel position (GptSettings::
// shared_jitter): every pixel's sample s then goes through the same position
// inside its pixel, so the offset of pixel p into its neighbour j starts with
// exactly the camera ray of j's own base path, and one intersection (and its
// shading data) serves the base path and the up to four offsets into j.
//
// The tile's pixels are traced up front, in Embree streams (every base path
// needs its own); ring pixels on first use, only when an offset asks
// (cached-path Russian roulette skips most offsets of dark pixels). The result is a pure function of the
// ray, so which tile traced a ring pixel does not change the image.
#pragma once

#include <vector>

#include "core/gradient/camera_hit.h"
#include "core/render/perspective_camera.h"
#include "core/render/tile_scheduler.h"

namespace gdvr {

class CameraHitCache {
 public:
  CameraHitCache(const FrameScene& scene, const PerspectiveCamera& camera) : scene_(scene), camera_(camera) {}

  // Starts sample index `s` over `tile` (plus a one-pixel ring) with film
  // position (x + jitter.x, y + jitter.y) for pixel (x, y); forgets the
  // previous entries without freeing their storage, and traces the tile's
  // own pixels (counted in `counters`).
  void begin(const Tile& tile, Vec2f jitter, PathCounters& counters);

  // The first hit of pixel (x, y)'s camera ray; (x, y) must lie in the tile or
  // its ring. The reference stays valid until the next begin().
  const CameraHit& at(int x, int y, PathCounters& counters);

 private:
  const FrameScene& scene_;
  const PerspectiveCamera& camera_;
  int x0_ = 0, y0_ = 0, width_ = 0, height_ = 0;  // the tile grown by the ring
  Vec2f jitter_;
  std::vector<CameraHit> hits_;
  std::vector<uint8_t> traced_;
};

}  // namespace gdvr
