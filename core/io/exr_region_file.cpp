#include "core/io/exr_region_file.h"

#include "core/io/image_io.h"

namespace gdvr {

Expected<std::unique_ptr<ExrRegionFile>> ExrRegionFile::open(const std::string& path) {
  auto extent = read_exr_extent(path);
  if (!extent.ok()) return extent.status();
  return std::unique_ptr<ExrRegionFile>(new ExrRegionFile(path, extent->width(), extent->height()));
}

Expected<LayeredImage> ExrRegionFile::read(const PixelRect& rect) const { return read_exr_region(path_, rect); }

}  // namespace gdvr
