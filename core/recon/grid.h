// Planar storage of one colour channel of a W-frame window: the solvers work
// on one float per pixel, index (t·height + y)·width + x, so rows of every
// frame are contiguous and the stencils vectorise along x.
#pragma once

#include <cstddef>
#include <vector>

namespace gdvr {

struct Grid {
  int width = 0, height = 0, frames = 0;

  size_t size() const { return size_t(width) * height * frames; }
  size_t frame_size() const { return size_t(width) * height; }
  int rows() const { return height * frames; }
  size_t index(int x, int y, int t) const { return (size_t(t) * height + y) * width + x; }
};

using Field = std::vector<float>;

}  // namespace gdvr
