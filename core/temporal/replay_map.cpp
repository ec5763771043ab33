#include "core/temporal/replay_map.h"

#include "core/temporal/motion_vectors.h"

namespace gdvr {

bool replay_source_pixel(const Image& backward, int qx, int qy, int* sx, int* sy) {
  if (backward.at(qx, qy, 2) == 0.0f) return false;
  const int x = qx + motion_pixel_offset(backward.at(qx, qy, 0));
  const int y = qy + motion_pixel_offset(backward.at(qx, qy, 1));
  if (x < 0 || y < 0 || x >= backward.width() || y >= backward.height()) return false;
  *sx = x;
  *sy = y;
  return true;
}

ReplayMap build_replay_map(const Image& backward) {
  ReplayMap map;
  map.width = backward.width();
  map.height = backward.height();
  map.sources.resize(size_t(map.width) * size_t(map.height));
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      ReplaySource& r = map.sources[size_t(y) * size_t(map.width) + size_t(x)];
      int sx, sy;
      if (!replay_source_pixel(backward, x, y, &sx, &sy)) {
        r.x = uint32_t(x);
        r.y = uint32_t(y);
        continue;
      }
      r.x = uint32_t(sx);
      r.y = uint32_t(sy);
      // δ = s − q − b: the rounding's remainder, in (−0.5, 0.5] per axis.
      r.shift = Vec2f(float(sx - x) - backward.at(x, y, 0), float(sy - y) - backward.at(x, y, 1));
    }
  return map;
}

ReplayPairs replay_pairs(const Image& forward, const Image& backward) {
  const int w = forward.width(), h = forward.height();
  ReplayPairs pairs;
  pairs.valid.assign(size_t(w) * size_t(h), 0);
  pairs.target = Image(w, h, 2);
  pairs.failure = Image(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool ok = forward.at(x, y, 2) != 0.0f;
      int qx = 0, qy = 0, sx = -1, sy = -1;
      if (ok) {
        qx = x + motion_pixel_offset(forward.at(x, y, 0));
        qy = y + motion_pixel_offset(forward.at(x, y, 1));
        ok = qx >= 0 && qy >= 0 && qx < w && qy < h && replay_source_pixel(backward, qx, qy, &sx, &sy) &&
             sx == x && sy == y;
      }
      if (ok) {
        pairs.valid[size_t(y) * size_t(w) + size_t(x)] = 1;
        pairs.target.at(x, y, 0) = float(qx - x);
        pairs.target.at(x, y, 1) = float(qy - y);
      } else {
        pairs.failure.at(x, y, 0) = 1.0f;
        ++pairs.failed;
      }
    }
  return pairs;
}

}  // namespace gdvr
