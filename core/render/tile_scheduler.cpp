#include "core/render/tile_scheduler.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <mutex>
#include <vector>

namespace gdvr {

int resolve_thread_count(int threads) {
  return threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
}

Status run_tiles(int width, int height, const TileRunOptions& options, const std::function<void(const Tile&)>& fn) {
  const int ts = std::max(1, options.tile_size);
  std::vector<Tile> tiles;
  for (int y = 0; y < height; y += ts)
    for (int x = 0; x < width; x += ts) tiles.push_back({x, y, std::min(x + ts, width), std::min(y + ts, height)});

  std::atomic<size_t> done{0};
  std::atomic<bool> stopped{false};
  std::mutex progress_mutex;
  tbb::task_arena arena(resolve_thread_count(options.threads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        if (options.cancel && options.cancel->load(std::memory_order_relaxed)) {
          stopped = true;
          return;
        }
        fn(tiles[i]);
        size_t n = ++done;
        if (options.on_progress) {
          std::lock_guard<std::mutex> lock(progress_mutex);
          options.on_progress(double(n) / double(tiles.size()));
        }
      }
    });
  });
  if (stopped) return cancelled("render cancelled");
  return Status::Ok();
}

}  // namespace gdvr
