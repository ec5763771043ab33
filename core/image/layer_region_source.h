// A frame's layers kept out of memory and read a rectangle at a time: run_job's
// buffers spilled under its memory limit (core/io/layer_spill_file.h) and the
// buffers EXRs a farm's tile task reads (core/io/exr_region_file.h). T-GPT's
// tiled window solve reads only each tile's part of them, so its finalize
// never holds whole frames of a window (docs/tgpt.md, "Memory").
#pragma once

#include "core/image/image.h"
#include "core/image/pixel_rect.h"
#include "core/util/status.h"

namespace gdvr {

class LayerRegionSource {
 public:
  virtual ~LayerRegionSource() = default;
  virtual int width() const = 0;
  virtual int height() const = 0;
  // Every layer cropped to `rect`; INVALID_ARGUMENT unless it lies inside the frame.
  virtual Expected<LayeredImage> read(const PixelRect& rect) const = 0;
};

}  // namespace gdvr
