// The window solve by tiles (docs/reconstruction.md, "Tiled solve"): each
// tile of a TileGrid is solved over its core plus halo, holding only that
// part of the window's frames, and keeps its core. The screened Poisson
// problem is local for α > 0 (its impulse response decays like e^(−α r)), so
// with a halo of a few decay lengths the tiled result agrees with the
// whole-frame solve to within the solver's own tolerance, and tile borders
// show no seam (TiledReconstructTest; figures in docs/benchmarks.md).
#pragma once

#include <functional>
#include <vector>

#include "core/recon/gradient_window.h"
#include "core/recon/recon_result.h"
#include "core/recon/recon_settings.h"
#include "core/recon/tile_grid.h"

namespace gdvr {

// The halo the L1 and L2 solves need at screening weight α: 6.4 decay
// lengths of the impulse response (kReconTileHaloDecayLengths), at least
// kMinReconTileHalo; 32 pixels at the default α = 0.2.
int tile_halo_for_alpha(double alpha);
// The halo `settings` asks for: tile_halo (tile_halo_for_alpha(alpha) where
// it is 0), and for the control variates
// (uniform, weighted) at least cv_iterations: after k Jacobi sweeps a pixel
// depends only on pixels within k steps, so that halo makes their tiled
// result exactly the whole-frame one.
int tile_halo_for(const ReconSettings& settings);
// Whether frames of width × height are solved by tiles under `settings`
// (tile_size > 0 and the frame larger than a tile in either axis).
bool solves_by_tiles(const ReconSettings& settings, int width, int height);
// The grid of `settings` for frames of width × height (one tile when not tiled).
Expected<TileGrid> tile_grid_for(const ReconSettings& settings, int width, int height);

// Every frame of `window` cropped to `rect` (values, variances, masks).
GradientWindow crop_window(const GradientWindow& window, const PixelRect& rect);

// The part of the window a tile solves over: every frame cropped to `padded`.
using TileWindowReader = std::function<Expected<GradientWindow>(const PixelRect& padded)>;
// Solves one tile's window; `core` is the tile's core in the tile window's
// coordinates (the stats count dropped constraints there only).
using TileSolver = std::function<Expected<ReconResult>(const GradientWindow& tile_window, const PixelRect& core)>;

// Receives each solved tile: `solved` covers the tile's padded region, and
// `core` is where the tile's core lies in it.
using TileSink = std::function<Status(const ReconTile& tile, const ReconResult& solved, const PixelRect& core)>;

// Solves the tiles `tile_indices` of `grid` (all when empty) one after the
// other, each read with `read`, solved with `solve` and handed to `sink`, so
// that no more than one tile's part of the window is held at a time. Returns
// the stats of all: iterations summed, the worst residual, dropped
// constraints counted once per pixel, wall seconds.
Expected<ReconStats> solve_tiles(const TileGrid& grid, int frames, const TileWindowReader& read,
                                 const TileSolver& solve, const TileSink& sink,
                                 const std::vector<int>& tile_indices = {});

// solve_tiles into `frames` full-size images holding every solved tile's core
// (pixels of tiles not solved stay 0).
Expected<ReconResult> reconstruct_tiled(const TileGrid& grid, int frames, const TileWindowReader& read,
                                        const TileSolver& solve, const std::vector<int>& tile_indices = {});

// An in-memory window by the tiles of `settings` (tile_grid_for), each tile
// solved with reconstruct(tile_window, settings).
Expected<ReconResult> reconstruct_tiled(const GradientWindow& window, const ReconSettings& settings);

}  // namespace gdvr
