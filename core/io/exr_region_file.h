// A frame's layers left in an EXR file and read a rectangle at a time
// (read_exr_region decompresses only the rectangle's rows): how a farm's tile
// task sees a frame's buffers, so that solving its tiles reads only their rows
// of the window's frames instead of every frame whole (docs/farm.md, "Stage 2
// by tiles").
#pragma once

#include <memory>
#include <string>

#include "core/image/layer_region_source.h"

namespace gdvr {

class ExrRegionFile final : public LayerRegionSource {
 public:
  // Reads the header only (the frame's size); each read() opens the file
  // again, so nothing stays open between the reads of a window's tiles.
  static Expected<std::unique_ptr<ExrRegionFile>> open(const std::string& path);

  int width() const override { return width_; }
  int height() const override { return height_; }
  Expected<LayeredImage> read(const PixelRect& rect) const override;
  const std::string& path() const { return path_; }

 private:
  ExrRegionFile(std::string path, int width, int height) : path_(std::move(path)), width_(width), height_(height) {}
  std::string path_;
  int width_ = 0, height_ = 0;
};

}  // namespace gdvr
