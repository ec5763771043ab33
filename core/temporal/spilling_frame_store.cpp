#include "core/temporal/spilling_frame_store.h"

namespace gdvr {

SpillingFrameStore::SpillingFrameStore(std::string spill_dir, long long memory_limit_bytes)
    : dir_(std::move(spill_dir)), limit_(memory_limit_bytes) {}

SpillingFrameStore::~SpillingFrameStore() = default;

Status SpillingFrameStore::put(int frame, LayeredImage layers) {
  if (layers.layers.empty()) return invalid_argument("spill store: frame " + std::to_string(frame) + " has no layers");
  const Image& first = layers.layers.front().image;
  if (width_ == 0) {
    width_ = first.width();
    height_ = first.height();
  } else if (first.width() != width_ || first.height() != height_) {
    return invalid_argument("spill store: frame " + std::to_string(frame) + " is " + std::to_string(first.width()) +
                            "x" + std::to_string(first.height()) + ", the shot's frames are " +
                            std::to_string(width_) + "x" + std::to_string(height_));
  }
  erase(frame);
  const long long bytes = layer_pixel_bytes(layers);
  if (limit_ < 0 || bytes_in_memory_ + bytes <= limit_) {
    bytes_in_memory_ += bytes;
    memory_[frame] = std::move(layers);
    return Status::Ok();
  }
  if (dir_.empty())
    return invalid_argument("spill store: frame " + std::to_string(frame) +
                            " exceeds the memory limit and no spill folder was given");
  auto file = LayerSpillFile::spill(dir_, layers);
  if (!file.ok()) return file.status();
  spilled_[frame] = std::move(file.value());
  most_spilled_ = std::max(most_spilled_, int(spilled_.size()));
  return Status::Ok();
}

void SpillingFrameStore::erase(int frame) {
  if (auto it = memory_.find(frame); it != memory_.end()) {
    bytes_in_memory_ -= layer_pixel_bytes(it->second);
    memory_.erase(it);
  }
  spilled_.erase(frame);  // closing the file frees its pixels
}

Expected<std::shared_ptr<const LayeredImage>> SpillingFrameStore::whole(int frame) const {
  return reader().read(frame, PixelRect::whole(width_, height_));
}

FrameRegionReader SpillingFrameStore::reader() const {
  FrameRegionReader r = in_memory_region_reader(width_, height_, [this](int frame) -> const LayeredImage* {
    auto it = memory_.find(frame);
    return it == memory_.end() ? nullptr : &it->second;
  });
  r.read = [this, in_memory = std::move(r.read)](int frame,
                                                 const PixelRect& rect) -> Expected<std::shared_ptr<const LayeredImage>> {
    auto it = spilled_.find(frame);
    if (it == spilled_.end()) return in_memory(frame, rect);
    auto region = it->second->read(rect);
    if (!region.ok()) return region.status();
    return std::shared_ptr<const LayeredImage>(std::make_shared<LayeredImage>(std::move(region.value())));
  };
  return r;
}

}  // namespace gdvr
