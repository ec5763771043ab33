#include "core/recon/tiled_reconstruct.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/image/image_region.h"
#include "core/recon/reconstruct.h"

namespace gdvr {

int tile_halo_for_alpha(double alpha) {
  // Frames are far below 2^31 pixels a side: clamp before converting.
  const double decay = std::ceil(std::min(kReconTileHaloDecayLengths / alpha, 1e9));
  return std::max(kMinReconTileHalo, int(decay));
}

int tile_halo_for(const ReconSettings& settings) {
  const int halo = settings.tile_halo > 0 ? settings.tile_halo : tile_halo_for_alpha(settings.alpha);
  const bool jacobi = settings.method == ReconMethod::kUniform || settings.method == ReconMethod::kWeighted;
  return jacobi ? std::max(halo, settings.cv_iterations) : halo;
}

bool solves_by_tiles(const ReconSettings& settings, int width, int height) {
  return settings.tile_size > 0 && (width > settings.tile_size || height > settings.tile_size);
}

Expected<TileGrid> tile_grid_for(const ReconSettings& settings, int width, int height) {
  const int size = solves_by_tiles(settings, width, height) ? settings.tile_size : std::max(width, height);
  return TileGrid::create(width, height, size, tile_halo_for(settings));
}

GradientWindow crop_window(const GradientWindow& window, const PixelRect& rect) {
  GradientWindow out;
  for (const auto& frame : window.frames) {
    auto f = std::make_shared<GradientFrame>();
    for (int k = 0; k < kTermCount; ++k) {
      f->values[size_t(k)] = crop_image(frame->values[size_t(k)], rect);
      f->variances[size_t(k)] = crop_image(frame->variances[size_t(k)], rect);
      f->valid[size_t(k)] = crop_mask(frame->valid[size_t(k)], frame->width(), rect);
    }
    f->data_weight = crop_image(frame->data_weight, rect);
    // Offsets are relative, so they crop as they are; a target outside the
    // tile drops its constraints (build_temporal_targets).
    f->temporal_target = crop_image(frame->temporal_target, rect);
    out.frames.push_back(std::move(f));
  }
  return out;
}

Expected<ReconStats> solve_tiles(const TileGrid& grid, int frames, const TileWindowReader& read,
                                 const TileSolver& solve, const TileSink& sink, const std::vector<int>& tile_indices) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<int> todo = tile_indices;
  if (todo.empty())
    for (int i = 0; i < grid.count(); ++i) todo.push_back(i);
  ReconStats total;
  for (int index : todo) {
    if (index < 0 || index >= grid.count())
      return invalid_argument("tiled solve: tile " + std::to_string(index) + " is not in the grid of " +
                              grid.to_string());
    const ReconTile& tile = grid.tile(index);
    const std::string where = "tile " + std::to_string(index) + " " + tile.core.to_string() + ": ";
    Expected<ReconResult> solved = invalid_argument("unset");
    const PixelRect core = tile.core.relative_to(tile.padded);
    {
      // The tile's window goes out of scope before the sink runs.
      Expected<GradientWindow> window = read(tile.padded);
      if (!window.ok()) return window.status().with_context(where);
      if (window->size() != frames || window->width() != tile.padded.width() ||
          window->height() != tile.padded.height())
        return internal_error(where + "read " + std::to_string(window->size()) + " frames of " +
                              std::to_string(window->width()) + "x" + std::to_string(window->height()) +
                              ", expected " + std::to_string(frames) + " of " + std::to_string(tile.padded.width()) +
                              "x" + std::to_string(tile.padded.height()));
      solved = solve(window.value(), core);
    }
    if (!solved.ok()) return solved.status().with_context(where);
    if (int(solved->frames.size()) != frames)
      return internal_error(where + "the solver returned " + std::to_string(solved->frames.size()) + " frames for " +
                            std::to_string(frames));
    GDVR_RETURN_IF_ERROR(sink(tile, solved.value(), core).with_context(where));
    const ReconStats& s = solved->stats;
    total.cg_iterations += s.cg_iterations;
    total.outer_iterations = std::max(total.outer_iterations, s.outer_iterations);
    total.relative_residual = std::max(total.relative_residual, s.relative_residual);
    for (int k = 0; k < kTermCount; ++k) {
      total.non_finite_constraints[size_t(k)] += s.non_finite_constraints[size_t(k)];
      total.masked_constraints[size_t(k)] += s.masked_constraints[size_t(k)];
    }
    total.non_finite_outputs += s.non_finite_outputs;
  }
  total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return total;
}

Expected<ReconResult> reconstruct_tiled(const TileGrid& grid, int frames, const TileWindowReader& read,
                                        const TileSolver& solve, const std::vector<int>& tile_indices) {
  ReconResult result;
  auto assemble = [&](const ReconTile& tile, const ReconResult& solved, const PixelRect& core) {
    if (result.frames.empty())
      for (int t = 0; t < frames; ++t) result.frames.emplace_back(grid.width(), grid.height(), solved.frames[0].channels());
    for (int t = 0; t < frames; ++t)
      paste_region(solved.frames[size_t(t)], core, &result.frames[size_t(t)], tile.core.x0, tile.core.y0);
    return Status::Ok();
  };
  auto stats = solve_tiles(grid, frames, read, solve, assemble, tile_indices);
  if (!stats.ok()) return stats.status();
  result.stats = stats.value();
  return result;
}

Expected<ReconResult> reconstruct_tiled(const GradientWindow& window, const ReconSettings& settings) {
  GDVR_RETURN_IF_ERROR(settings.validate());
  GDVR_RETURN_IF_ERROR(window.validate());
  auto grid = tile_grid_for(settings, window.width(), window.height());
  if (!grid.ok()) return grid.status();
  return reconstruct_tiled(
      grid.value(), window.size(),
      [&](const PixelRect& padded) -> Expected<GradientWindow> { return crop_window(window, padded); },
      [&](const GradientWindow& tile, const PixelRect& core) { return reconstruct(tile, settings, core); });
}

}  // namespace gdvr
