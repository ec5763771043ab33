#include "core/image/image_region.h"

#include <algorithm>

namespace gdvr {

Image crop_image(const Image& image, const PixelRect& rect) {
  if (image.empty()) return {};
  Image out(rect.width(), rect.height(), image.channels());
  paste_region(image, rect, &out, 0, 0);
  return out;
}

LayeredImage crop_layers(const LayeredImage& image, const PixelRect& rect) {
  LayeredImage out;
  for (const ImageLayer& l : image.layers) out.add(l.name, l.channels, crop_image(l.image, rect));
  return out;
}

std::vector<uint8_t> crop_mask(const std::vector<uint8_t>& mask, int width, const PixelRect& rect) {
  if (mask.empty()) return {};
  std::vector<uint8_t> out(rect.pixel_count());
  for (int y = rect.y0; y < rect.y1; ++y)
    std::copy_n(mask.begin() + (size_t(y) * width + rect.x0), rect.width(),
                out.begin() + size_t(y - rect.y0) * rect.width());
  return out;
}

void paste_region(const Image& src, const PixelRect& src_rect, Image* dst, int dst_x, int dst_y) {
  const int C = src.channels();
  const size_t row = size_t(src_rect.width()) * C;
  for (int y = src_rect.y0; y < src_rect.y1; ++y) {
    const float* from = src.data().data() + (size_t(y) * src.width() + src_rect.x0) * C;
    float* to = dst->data().data() + (size_t(dst_y + y - src_rect.y0) * dst->width() + dst_x) * C;
    std::copy_n(from, row, to);
  }
}

}  // namespace gdvr
