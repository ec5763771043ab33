// A rectangle of pixels [x0, x1) × [y0, y1): a tile of a frame, or the part of
// a frame's buffers a tile reads (docs/reconstruction.md, "Tiled solve").
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>

namespace gdvr {

struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;

  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  size_t pixel_count() const { return size_t(std::max(0, width())) * size_t(std::max(0, height())); }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  // Whether `inner` lies inside this rectangle.
  bool contains(const PixelRect& inner) const {
    return inner.x0 >= x0 && inner.y0 >= y0 && inner.x1 <= x1 && inner.y1 <= y1;
  }
  // The same rectangle in the coordinates of a crop starting at `origin`.
  PixelRect relative_to(const PixelRect& origin) const { return {x0 - origin.x0, y0 - origin.y0, x1 - origin.x0, y1 - origin.y0}; }
  bool operator==(const PixelRect& o) const { return x0 == o.x0 && y0 == o.y0 && x1 == o.x1 && y1 == o.y1; }

  static PixelRect whole(int width, int height) { return {0, 0, width, height}; }
  std::string to_string() const {
    return "[" + std::to_string(x0) + "," + std::to_string(x1) + ")x[" + std::to_string(y0) + "," + std::to_string(y1) + ")";
  }
};

}  // namespace gdvr
