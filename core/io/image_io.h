// Reading and writing images: the one place that wraps OpenEXR and the
// PNG/JPEG codecs. Pixels in memory are always linear float.
#pragma once

#include <string>

#include "core/image/image.h"
#include "core/image/pixel_rect.h"
#include "core/util/status.h"

namespace gdvr {

// Reads an RGB image (EXR: the R,G,B channels of the main layer; PNG/JPEG:
// decoded from sRGB to linear unless `raw`). Result has 3 channels.
Expected<Image> read_rgb_image(const std::string& path, bool raw = false);

// Writes every layer as float (or half for `half_float`) channels of one
// multi-layer EXR, atomically (temporary file + rename): "R,G,B" for the
// unnamed layer, "<layer>.<channel>" for the others, but a bare "<channel>"
// where the layer is named as its channel (the depth layer "Z" becomes EXR's
// standard "Z" channel; read_exr turns it back into that layer).
// The codec is lossless either way; `compression` trades file size for write
// time (docs/renderer.md, "EXR codecs").
enum class ExrCompression { kZip, kZips, kRle, kPiz, kNone };
Status write_exr(const std::string& path, const LayeredImage& image, bool half_float = false,
                 ExrCompression compression = ExrCompression::kZip);
// The job-file names of the codecs ("zip", "zips", "rle", "piz", "none"),
// as OpenEXR calls them.
Expected<ExrCompression> parse_exr_compression(const std::string& name);
// Reads every channel of an EXR back into layers (the inverse of write_exr).
Expected<LayeredImage> read_exr(const std::string& path);
// read_exr cropped to `rect` (in the image's pixels: (0, 0) is the data
// window's top-left corner), without reading the rest of the file: only the
// rect's scanlines are decompressed, and only its columns are kept. A farm
// tile task reads its tile's part of a frame's buffers so (docs/farm.md). A
// rect that is empty or not inside the data window is INVALID_ARGUMENT.
Expected<LayeredImage> read_exr_region(const std::string& path, const PixelRect& rect);
// The pixels read_exr would return, [0, width) x [0, height), from the header
// alone (the first part's data window).
Expected<PixelRect> read_exr_extent(const std::string& path);

// Writes an 8-bit RGB PNG from already display-encoded values in [0, 1].
Status write_png8(const std::string& path, const Image& display_rgb);

}  // namespace gdvr
