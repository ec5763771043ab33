// Runs a per-tile function over an image on a TBB arena of a given size. Pixels
// belong to exactly one tile and each tile's work is a pure function of its
// pixels' sample streams, so results do not depend on thread count or order.
#pragma once

#include <atomic>
#include <functional>

#include "core/util/status.h"

namespace gdvr {

struct Tile {
  int x0, y0, x1, y1;  // [x0, x1) x [y0, y1)
};

struct TileRunOptions {
  int threads = 0;      // 0: all cores
  int tile_size = 16;
  const std::atomic<bool>* cancel = nullptr;      // checked before every tile
  std::function<void(double fraction)> on_progress;  // called after tiles finish
};

// Returns kCancelled when *cancel was set before all tiles ran.
Status run_tiles(int width, int height, const TileRunOptions& options, const std::function<void(const Tile&)>& fn);

int resolve_thread_count(int threads);

}  // namespace gdvr
