// How visible the borders between tiles are in a tiled solve's image: the
// mean |second difference| across the borders of the tiles' cores against
// the same everywhere else (docs/reconstruction.md, "Tiled solve"). A seam
// (a step or kink where two tiles meet) raises the first above the second;
// comparing both with the whole-frame solve's own figures at the same pixels
// separates seams from what the image holds anyway.
#pragma once

#include "core/image/image.h"
#include "core/recon/tile_grid.h"

namespace gdvr {

struct SeamMetric {
  double border = 0;     // mean |second difference| straddling a border between cores
  double elsewhere = 0;  // the same over every other interior pixel
  double ratio() const { return elsewhere > 0 ? border / elsewhere : 0; }
};

// Horizontal second differences I(x−1) − 2I(x) + I(x+1) at the two columns on
// either side of each vertical border, vertical ones at the two rows beside
// each horizontal border, all channels. The image must be grid-sized.
SeamMetric tile_seam_metric(const Image& image, const TileGrid& grid);

}  // namespace gdvr
