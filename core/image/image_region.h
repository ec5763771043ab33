// Copying rectangles of pixels out of and into images: how a tiled solve
// takes a tile's part of a frame's buffers and puts its result back.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image/image.h"
#include "core/image/pixel_rect.h"

namespace gdvr {

// The pixels of `rect` (which must lie inside the image) as an image of their own.
Image crop_image(const Image& image, const PixelRect& rect);
// Every layer cropped to `rect`.
LayeredImage crop_layers(const LayeredImage& image, const PixelRect& rect);
// A per-pixel byte mask (width × height, row-major) cropped to `rect`; empty stays empty.
std::vector<uint8_t> crop_mask(const std::vector<uint8_t>& mask, int width, const PixelRect& rect);
// Copies `src_rect` of `src` to `dst` with its top-left corner at (dst_x, dst_y).
// Channel counts must match; the rectangle must fit both images.
void paste_region(const Image& src, const PixelRect& src_rect, Image* dst, int dst_x, int dst_y);

}  // namespace gdvr
