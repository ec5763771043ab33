// Float images and named layer sets. A frame's outputs (final image, primal,
// gradients, variances, failure rates) are one LayeredImage; the EXR writer
// names channels "<layer>.<channel>" ("dx.R"), the main layer plain "R,G,B".
#pragma once

#include <string>
#include <vector>

#include "core/math/vec.h"

namespace gdvr {

class Image {
 public:
  Image() = default;
  Image(int width, int height, int channels) : width_(width), height_(height), channels_(channels),
      data_(size_t(width) * height * channels, 0.0f) {}
  // Takes `data` (width × height × channels floats, row-major) as its pixels:
  // for a producer that fills rows as it goes, touching memory only as it
  // writes (GradientFilm::resolve), where a zeroed image would be resident at once.
  Image(int width, int height, int channels, std::vector<float> data)
      : width_(width), height_(height), channels_(channels), data_(std::move(data)) {
    data_.resize(size_t(width) * height * channels, 0.0f);
  }

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  size_t pixel_count() const { return size_t(width_) * height_; }
  bool empty() const { return data_.empty(); }

  float& at(int x, int y, int c) { return data_[(size_t(y) * width_ + x) * channels_ + c]; }
  float at(int x, int y, int c) const { return data_[(size_t(y) * width_ + x) * channels_ + c]; }
  // RGB access; requires channels() >= 3.
  Rgb rgb(int x, int y) const {
    const float* p = &data_[(size_t(y) * width_ + x) * channels_];
    return {p[0], p[1], p[2]};
  }
  void prefetch_rgb(int x, int y) const { __builtin_prefetch(&data_[(size_t(y) * width_ + x) * channels_]); }
  void set_rgb(int x, int y, Rgb c) {
    float* p = &data_[(size_t(y) * width_ + x) * channels_];
    p[0] = c.r; p[1] = c.g; p[2] = c.b;
  }
  std::vector<float>& data() { return data_; }
  const std::vector<float>& data() const { return data_; }

 private:
  int width_ = 0, height_ = 0, channels_ = 0;
  std::vector<float> data_;
};

struct ImageLayer {
  std::string name;                    // "" for the main RGB image, else "primal", "dx", ...
  std::vector<std::string> channels;   // {"R","G","B"} or {"Y"}
  Image image;
};

struct LayeredImage {
  std::vector<ImageLayer> layers;

  const ImageLayer* find(const std::string& name) const {
    for (const auto& l : layers)
      if (l.name == name) return &l;
    return nullptr;
  }
  ImageLayer& add(std::string name, std::vector<std::string> channels, Image image) {
    layers.push_back({std::move(name), std::move(channels), std::move(image)});
    return layers.back();
  }
};

}  // namespace gdvr
