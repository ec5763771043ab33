// A farm's tiled finalize (docs/farm.md, "Stage 2 by tiles"): tasks that each
// solve some tiles of the reconstruction's tile grid write, per frame and
// tile, the tile's core of the reconstructed image (before the direct light)
// as OUT/tiles/solved_0001_t0003.exr; a last finalize pastes a frame's parts
// together and writes the frame as one task would have, bit for bit.
//
// The parts live in the output folder, not beside the buffers: they depend
// on the finalize-only settings (the reconstruction), and a re-finalize with
// other settings goes to another --out (docs/farm.md).
#pragma once

#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/recon/tile_grid.h"
#include "core/util/status.h"

namespace gdvr::farm {

std::string tile_part_path(const std::string& out_dir, int frame, int tile);  // OUT/tiles/solved_0001_t0003.exr

// Writes the core of `tile` cut from `solved` (a frame-sized image whose other
// tiles may be 0), atomically.
Status write_tile_part(const std::string& out_dir, int frame, const TileGrid& grid, int tile, const Image& solved);
// Whether any part of `frame` exists (then its finalize assembles, and needs no window).
bool has_tile_parts(const std::string& out_dir, int frame);
// The tiles of `grid` whose part of `frame` is missing.
std::vector<int> missing_tile_parts(const std::string& out_dir, int frame, const TileGrid& grid);
// Every part of `frame` pasted into one image; NOT_FOUND naming the missing
// tiles, INVALID_ARGUMENT for a part whose size is not its tile's core (a
// part of another tile grid).
Expected<Image> assemble_tile_parts(const std::string& out_dir, int frame, const TileGrid& grid);
// Removes the parts of `frame` (once the frame is written).
void remove_tile_parts(const std::string& out_dir, int frame, const TileGrid& grid);

}  // namespace gdvr::farm
