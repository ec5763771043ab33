#include "core/farm/tile_parts.h"

#include <cstdio>
#include <filesystem>

#include "core/image/image_region.h"
#include "core/io/image_io.h"

namespace gdvr::farm {
namespace fs = std::filesystem;

namespace {

std::string frame_prefix(int frame) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "solved_%04d_t", frame);
  return buf;
}

}  // namespace

std::string tile_part_path(const std::string& out_dir, int frame, int tile) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%04d.exr", tile);
  return (fs::path(out_dir) / "tiles" / (frame_prefix(frame) + buf)).string();
}

Status write_tile_part(const std::string& out_dir, int frame, const TileGrid& grid, int tile, const Image& solved) {
  if (tile < 0 || tile >= grid.count())
    return invalid_argument("tile " + std::to_string(tile) + " is not in the grid of " + grid.to_string());
  std::error_code ec;
  fs::create_directories(fs::path(out_dir) / "tiles", ec);
  if (ec) return internal_error(out_dir + "/tiles: cannot create: " + ec.message());
  LayeredImage part;
  part.add("", {"R", "G", "B"}, crop_image(solved, grid.tile(tile).core));
  return write_exr(tile_part_path(out_dir, frame, tile), part);
}

bool has_tile_parts(const std::string& out_dir, int frame) {
  std::error_code ec;
  const std::string prefix = frame_prefix(frame);
  for (fs::directory_iterator it(fs::path(out_dir) / "tiles", ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) == 0 && name.size() > 4 && name.compare(name.size() - 4, 4, ".exr") == 0) return true;
  }
  return false;
}

std::vector<int> missing_tile_parts(const std::string& out_dir, int frame, const TileGrid& grid) {
  std::vector<int> missing;
  std::error_code ec;
  for (int t = 0; t < grid.count(); ++t)
    if (!fs::exists(tile_part_path(out_dir, frame, t), ec)) missing.push_back(t);
  return missing;
}

Expected<Image> assemble_tile_parts(const std::string& out_dir, int frame, const TileGrid& grid) {
  const std::vector<int> missing = missing_tile_parts(out_dir, frame, grid);
  if (!missing.empty()) {
    std::string list;
    for (int t : missing) list += (list.empty() ? "" : ",") + std::to_string(t);
    return not_found("frame " + std::to_string(frame) + ": tile parts missing for tile(s) " + list + " of " +
                     grid.to_string() + " (" + tile_part_path(out_dir, frame, missing.front()) +
                     "); run gdvr-farm finalize --tiles for them first");
  }
  Image out;
  for (int t = 0; t < grid.count(); ++t) {
    const std::string path = tile_part_path(out_dir, frame, t);
    auto part = read_exr(path);
    if (!part.ok()) return part.status();
    const ImageLayer* rgb = part->find("");
    const PixelRect core = grid.tile(t).core;
    if (!rgb || rgb->image.width() != core.width() || rgb->image.height() != core.height() || rgb->image.channels() != 3)
      return invalid_argument(path + ": not the " + std::to_string(core.width()) + "x" + std::to_string(core.height()) +
                              " RGB core of tile " + std::to_string(t) + " of " + grid.to_string() +
                              " (a part of another tile grid? finalize into a fresh --out)");
    if (out.empty()) out = Image(grid.width(), grid.height(), 3);
    paste_region(rgb->image, PixelRect::whole(core.width(), core.height()), &out, core.x0, core.y0);
  }
  return out;
}

void remove_tile_parts(const std::string& out_dir, int frame, const TileGrid& grid) {
  for (int t = 0; t < grid.count(); ++t) {
    std::error_code ec;
    fs::remove(tile_part_path(out_dir, frame, t), ec);
  }
}

}  // namespace gdvr::farm
