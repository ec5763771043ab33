#include "core/recon/tile_seams.h"

#include <cmath>
#include <vector>

namespace gdvr {

namespace {

// Per column (or row) index: whether a second difference centred there
// straddles a border between two tiles' cores.
std::vector<bool> beside_borders(int n, const std::vector<int>& borders) {
  std::vector<bool> out(size_t(std::max(n, 0)), false);
  for (int b : borders)
    for (int i : {b - 1, b})
      if (i >= 0 && i < n) out[size_t(i)] = true;
  return out;
}

}  // namespace

SeamMetric tile_seam_metric(const Image& image, const TileGrid& grid) {
  std::vector<int> vertical, horizontal;  // x of vertical borders, y of horizontal ones
  for (const ReconTile& t : grid.tiles()) {
    if (t.core.x0 > 0) vertical.push_back(t.core.x0);
    if (t.core.y0 > 0) horizontal.push_back(t.core.y0);
  }
  const int W = image.width(), H = image.height(), C = image.channels();
  const std::vector<bool> at_column = beside_borders(W, vertical), at_row = beside_borders(H, horizontal);
  double border = 0, elsewhere = 0;
  long long n_border = 0, n_elsewhere = 0;
  auto add = [&](bool straddles, double v) {
    (straddles ? border : elsewhere) += std::fabs(v);
    ++(straddles ? n_border : n_elsewhere);
  };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int c = 0; c < C; ++c) {
        if (x > 0 && x + 1 < W)
          add(at_column[size_t(x)], double(image.at(x - 1, y, c)) - 2.0 * image.at(x, y, c) + image.at(x + 1, y, c));
        if (y > 0 && y + 1 < H)
          add(at_row[size_t(y)], double(image.at(x, y - 1, c)) - 2.0 * image.at(x, y, c) + image.at(x, y + 1, c));
      }
  SeamMetric m;
  m.border = n_border ? border / double(n_border) : 0;
  m.elsewhere = n_elsewhere ? elsewhere / double(n_elsewhere) : 0;
  return m;
}

}  // namespace gdvr
