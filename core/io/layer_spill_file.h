// A frame's layers spilled to a raw file so that any rectangle of them can be
// read back without reading the rest: T-GPT's memory-bounded stage 2 keeps
// buffered stage-1 frames on disk and each tile of a window solve reads only
// its part of them (docs/tgpt.md, "Memory").
//
// Layout: a header (magic, width, height, the layers' names and channel
// names), then each layer's pixels row-major as native floats (the file is a
// scratch file of one process, never exchanged between machines). A region
// is one read per row and layer.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/image/layer_region_source.h"

namespace gdvr {

// Writes every layer of `image` (all of one size) to `path`, replacing it.
Status write_layer_spill(const std::string& path, const LayeredImage& image);

// The bytes of `image`'s pixels (what spilling it frees).
long long layer_pixel_bytes(const LayeredImage& image);

class LayerSpillFile final : public LayerRegionSource {
 public:
  // Reads and checks the header; the pixels stay on disk.
  static Expected<std::unique_ptr<LayerSpillFile>> open(const std::string& path);
  // Writes `image` to a new file in `dir`, opens it and removes its name: the
  // pixels live until the returned file is closed, and nothing is left
  // behind whatever happens to the process.
  static Expected<std::unique_ptr<LayerSpillFile>> spill(const std::string& dir, const LayeredImage& image);
  ~LayerSpillFile();
  LayerSpillFile(const LayerSpillFile&) = delete;
  LayerSpillFile& operator=(const LayerSpillFile&) = delete;

  int width() const override { return width_; }
  int height() const override { return height_; }
  // Every layer cropped to `rect`, which must lie inside the frame.
  Expected<LayeredImage> read(const PixelRect& rect) const override;

 private:
  LayerSpillFile() = default;
  struct Layer {
    std::string name;
    std::vector<std::string> channels;
    long long offset = 0;  // of its first pixel in the file
  };
  std::string path_;
  int fd_ = -1;
  int width_ = 0, height_ = 0;
  std::vector<Layer> layers_;
};

}  // namespace gdvr
