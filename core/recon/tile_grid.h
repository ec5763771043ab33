// How a tiled window solve splits a frame (docs/reconstruction.md, "Tiled
// solve"): tiles whose cores cover the frame once, each solved on its core
// grown by a halo on every side (clamped to the frame). With α > 0 the
// screened Poisson solve is local: a pixel's influence decays within a few
// tens of pixels, so the solution on a core barely depends on what lies
// beyond its halo, and each tile keeps its core and discards the halo.
#pragma once

#include <string>
#include <vector>

#include "core/image/pixel_rect.h"
#include "core/util/status.h"

namespace gdvr {

struct ReconTile {
  PixelRect core;    // the pixels this tile's solve outputs
  PixelRect padded;  // the pixels it solves over: core + halo, inside the frame
};

class TileGrid {
 public:
  // Tiles of at most `tile_size` × `tile_size` core pixels (cores of near-equal
  // size, so no sliver tile at the right or bottom), halos of `halo` pixels.
  // tile_size ≥ 1 and halo ≥ 0; a frame no larger than tile_size is one tile.
  static Expected<TileGrid> create(int width, int height, int tile_size, int halo);

  int width() const { return width_; }
  int height() const { return height_; }
  int columns() const { return columns_; }
  int rows() const { return rows_; }
  int halo() const { return halo_; }
  int count() const { return int(tiles_.size()); }
  // Row-major: tile (column, row) is tiles()[row * columns() + column].
  const std::vector<ReconTile>& tiles() const { return tiles_; }
  const ReconTile& tile(int index) const { return tiles_[size_t(index)]; }
  std::string to_string() const;

 private:
  int width_ = 0, height_ = 0, columns_ = 0, rows_ = 0, halo_ = 0;
  std::vector<ReconTile> tiles_;
};

}  // namespace gdvr
