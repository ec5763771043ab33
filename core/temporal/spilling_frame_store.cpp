#include "core/temporal/spilling_frame_store.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>


namespace gdvr {

namespace {

long long pixel_bytes(const LayeredImage& l) {
  long long n = 0;
  for (const ImageLayer& layer : l.layers) n += (long long)layer.image.data().size() * (long long)sizeof(float);
  return n;
}

}  // namespace

SpillingFrameStore::SpillingFrameStore(std::string spill_dir, long long memory_limit_bytes)
    : dir_(std::move(spill_dir)), limit_(memory_limit_bytes) {}

SpillingFrameStore::~SpillingFrameStore() {
  for (auto& [frame, file] : spilled_) {
    file.reset();
    std::error_code ec;
    std::filesystem::remove(spill_path(frame), ec);
  }
}

std::string SpillingFrameStore::spill_path(int frame) const {
  // The process id keeps two runs sharing a folder apart.
  char name[64];
  std::snprintf(name, sizeof name, "gdvr_spill_%d_%06d.raw", int(::getpid()), frame);
  return (std::filesystem::path(dir_) / name).string();
}

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
  const long long bytes = pixel_bytes(layers);
  if (limit_ < 0 || bytes_in_memory_ + bytes <= limit_) {
    bytes_in_memory_ += bytes;
    memory_[frame] = std::move(layers);
    return Status::Ok();
  }
  if (dir_.empty())
    return invalid_argument("spill store: frame " + std::to_string(frame) +
                            " exceeds the memory limit and no spill folder was given");
  const std::string path = spill_path(frame);
  GDVR_RETURN_IF_ERROR(write_layer_spill(path, layers));
  auto file = LayerSpillFile::open(path);
  if (!file.ok()) return file.status();
  spilled_[frame] = std::move(file.value());
  most_spilled_ = std::max(most_spilled_, int(spilled_.size()));
  return Status::Ok();
}

void SpillingFrameStore::erase(int frame) {
  if (auto it = memory_.find(frame); it != memory_.end()) {
    bytes_in_memory_ -= pixel_bytes(it->second);
    memory_.erase(it);
  }
  if (auto it = spilled_.find(frame); it != spilled_.end()) {
    spilled_.erase(it);
    std::error_code ec;
    std::filesystem::remove(spill_path(frame), ec);
  }
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
