#include "core/recon/tile_grid.h"

#include <algorithm>

namespace gdvr {

namespace {

// Split [0, n) into `parts` spans of near-equal length: span i is [cut(i), cut(i+1)).
int cut(int n, int parts, int i) { return int((long long)n * i / parts); }

}  // namespace

Expected<TileGrid> TileGrid::create(int width, int height, int tile_size, int halo) {
  if (width < 1 || height < 1)
    return invalid_argument("tile grid: frame is " + std::to_string(width) + "x" + std::to_string(height) +
                            ", needs at least one pixel");
  if (tile_size < 1) return invalid_argument("tile grid: tile_size must be >= 1, got " + std::to_string(tile_size));
  if (halo < 0) return invalid_argument("tile grid: halo must be >= 0, got " + std::to_string(halo));
  TileGrid g;
  g.width_ = width;
  g.height_ = height;
  g.halo_ = halo;
  g.columns_ = (width + tile_size - 1) / tile_size;
  g.rows_ = (height + tile_size - 1) / tile_size;
  for (int r = 0; r < g.rows_; ++r)
    for (int c = 0; c < g.columns_; ++c) {
      ReconTile t;
      t.core = {cut(width, g.columns_, c), cut(height, g.rows_, r), cut(width, g.columns_, c + 1),
                cut(height, g.rows_, r + 1)};
      t.padded = {std::max(0, t.core.x0 - halo), std::max(0, t.core.y0 - halo), std::min(width, t.core.x1 + halo),
                  std::min(height, t.core.y1 + halo)};
      g.tiles_.push_back(t);
    }
  return g;
}

std::string TileGrid::to_string() const {
  return std::to_string(columns_) + "x" + std::to_string(rows_) + " tiles over " + std::to_string(width_) + "x" +
         std::to_string(height_) + ", halo " + std::to_string(halo_);
}

}  // namespace gdvr
