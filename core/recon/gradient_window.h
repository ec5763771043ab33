// W consecutive frames of one shot, solved together (Manzi et al. 2016;
// docs/reconstruction.md). Frames
// are shared, not copied, so overlapping sliding windows reuse the buffers.
#pragma once

#include <memory>
#include <vector>

#include "core/recon/gradient_frame.h"

namespace gdvr {

struct GradientWindow {
  std::vector<std::shared_ptr<const GradientFrame>> frames;

  int size() const { return int(frames.size()); }
  int width() const { return frames.empty() ? 0 : frames[0]->width(); }
  int height() const { return frames.empty() ? 0 : frames[0]->height(); }
  int channels() const { return frames.empty() ? 0 : frames[0]->channels(); }
  // True when any frame except the last carries a temporal buffer; only then
  // does the solve couple frames (W = 1 or no temporal buffers ≡ spatial).
  bool has_temporal_terms() const;

  // Non-empty, every frame valid and of one shape; names the offending frame.
  Status validate() const;

  static GradientWindow single(GradientFrame frame) {
    GradientWindow w;
    w.frames.push_back(std::make_shared<const GradientFrame>(std::move(frame)));
    return w;
  }
};

}  // namespace gdvr
