// Camera rays of one sample index over a tile where every pixel has its own
// sub-pixel position (GptSettings::shared_jitter off, as in T-GPT's half
// passes): each pixel's base ray and, when asked, the rays of its offsets into
// the four neighbours (the same position moved by one pixel), traced up front
// in Embree streams rather than one at a time inside each path. Camera rays
// are coherent, and they are a third of a T-GPT sample's rays (a base ray and
// four offsets' among about 15).
//
// CameraHitCache is the shared-position counterpart, where the offsets of p
// into j reuse j's base ray; here every ray is its own.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "core/gradient/camera_hit.h"
#include "core/gradient/gradient_film.h"
#include "core/render/perspective_camera.h"
#include "core/render/tile_scheduler.h"

namespace gdvr {

class TileCameraRays {
 public:
  TileCameraRays(const FrameScene& scene, const PerspectiveCamera& camera) : scene_(scene), camera_(camera) {}

  // Traces the rays of `tile` for film position (x + j.x, y + j.y), j =
  // jitter(x, y): every pixel's own, and with `offsets` also the offsets'
  // into the neighbours inside the width × height image (counted in
  // `counters`). Forgets the previous tile's hits without freeing them.
  void begin(const Tile& tile, int width, int height, const std::function<Vec2f(int x, int y)>& jitter, bool offsets,
             PathCounters& counters);

  // Pixel (x, y)'s base ray's first hit; (x, y) must lie in the tile.
  const CameraHit& base(int x, int y) const { return hits_[slot(x, y)][0]; }
  // The first hit of the offset of (x, y) in direction o (kOffsetDx/Dy);
  // begin() must have traced offsets, and the neighbour must lie in the image.
  const CameraHit& offset(int x, int y, int o) const { return hits_[slot(x, y)][size_t(1 + o)]; }

 private:
  size_t slot(int x, int y) const { return size_t(y - tile_.y0) * size_t(tile_.x1 - tile_.x0) + size_t(x - tile_.x0); }

  const FrameScene& scene_;
  const PerspectiveCamera& camera_;
  Tile tile_{0, 0, 0, 0};
  std::vector<std::array<CameraHit, 1 + kOffsetCount>> hits_;
};

}  // namespace gdvr
