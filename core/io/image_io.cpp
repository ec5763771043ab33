// OpenEXR and stb_image/stb_image_write behind the image_io.h contract. Every
// library call is wrapped in try/catch here: OpenEXR reports corrupt files by
// throwing, and core never lets exceptions cross its API.
#include "core/io/image_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <thread>

#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <ImfOutputFile.h>
#include <ImfPartType.h>
#include <ImfRgbaFile.h>
#include <ImfStringVectorAttribute.h>
#include <ImfThreading.h>

// Static linkage keeps stb's symbols private to this file, so a texture loader
// elsewhere in core may include its own stb implementation without clashes.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#include <stb/stb_image.h>
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include "core/image/image_region.h"
#include "core/io/atomic_file.h"

namespace gdvr {
namespace {

// Far beyond any frame gdvr renders; a header claiming more is corrupt or
// hostile, and trusting it would make us allocate gigabytes before failing.
constexpr int64_t kMaxDimension = 32768;
constexpr int64_t kMaxPixels = int64_t(1) << 27;  // 134 Mpixel, ~1.6 GB as float RGB

// Custom header attribute recording the writer's channel order: EXR stores
// channels sorted by name, which would turn "R,G,B" into "B,G,R" on read.
const char* const kChannelOrderAttribute = "gdvrChannelOrder";

Status check_dimensions(const std::string& path, int64_t width, int64_t height) {
  if (width <= 0 || height <= 0 || width > kMaxDimension || height > kMaxDimension ||
      width * height > kMaxPixels) {
    return invalid_argument(path + ": implausible image size " + std::to_string(width) + "x" +
                            std::to_string(height));
  }
  return Status::Ok();
}

// OpenEXR sizes its line and tile buffers from the header before we see the
// data window; its own limits stop a hostile header there. And it compresses
// and decompresses one chunk of lines at a time on the calling thread unless
// given a pool: with a thread per core, the farm's finalize (zlib 61 % of its
// cycles) ran 1.4x faster, files byte-identical (docs/benchmarks.md). Process-wide,
// but OpenEXR is only used through this file.
void configure_openexr() {
  static std::once_flag once;
  std::call_once(once, [] {
    Imf::Header::setMaxImageSize(int(kMaxDimension), int(kMaxDimension));
    Imf::Header::setMaxTileSize(int(kMaxDimension), int(kMaxDimension));
    Imf::setGlobalThreadCount(int(std::max(1u, std::thread::hardware_concurrency())));
  });
}

bool has_exr_magic(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) return false;
  unsigned char magic[4] = {};
  if (std::fread(magic, 1, 4, f.get()) != 4) return false;
  return magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
}

bool file_exists(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  return f != nullptr;
}

// IEC 61966-2-1 piecewise sRGB decoding (not a 2.2 gamma: the linear toe
// matters for dark texture values).
float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

// The channels a bare name (no layer prefix) gives the main image: its
// colour, alpha and luminance. Any other bare channel is a layer of its own
// named as the channel, as EXR spells its standard depth channel: "Z" beside
// "R,G,B" is the depth layer, not a fourth colour channel.
bool is_main_image_channel(const std::string& channel) {
  return channel == "R" || channel == "G" || channel == "B" || channel == "A" || channel == "Y";
}

// Splits "dx.R" into ("dx", "R") at the last '.', "R" into ("", "R") and
// "Z" into ("Z", "Z").
std::pair<std::string, std::string> split_channel_name(const std::string& full) {
  const size_t dot = full.rfind('.');
  if (dot == std::string::npos) return {is_main_image_channel(full) ? "" : full, full};
  return {full.substr(0, dot), full.substr(dot + 1)};
}

// The inverse: a layer's channel named as the layer itself is written bare.
std::string full_channel_name(const std::string& layer, const std::string& channel) {
  return layer.empty() || layer == channel ? channel : layer + "." + channel;
}

// Order used when a file carries no gdvrChannelOrder attribute (files from
// other tools): colour channels in their conventional order, then by name.
int channel_rank(const std::string& c) {
  static const std::array<const char*, 7> kOrder = {"R", "G", "B", "A", "X", "Y", "Z"};
  for (size_t i = 0; i < kOrder.size(); ++i)
    if (c == kOrder[i]) return int(i);
  return int(kOrder.size());
}

bool is_deep(const Imf::Header& header) {
  return header.hasType() &&
         (header.type() == Imf::DEEPSCANLINE || header.type() == Imf::DEEPTILE);
}

// ---- EXR reading -----------------------------------------------------------

// OpenEXR stores and decodes whole scanlines (readPixels fills every column of
// the data window), so a region read that keeps only some columns stages its
// rows at full width, a band at a time, and copies the columns out. A band is
// about kRegionBandBytes of pixels and a whole number of kRegionBandAlign rows
// from the data window's top: 32 rows is a whole number of every compression's
// chunks but DWAB's (256), so consecutive bands never decompress one chunk twice.
constexpr size_t kRegionBandBytes = size_t(4) << 20;
constexpr int kRegionBandAlign = 32;

// Reads rows [y0, y1) of the image (0: the data window's top) of the channel
// groups `layers` into `dst` (one full-width image per group, its first row
// row y0): one frame buffer for every group, so that each chunk of the file is
// decompressed once, not once per layer. FLOAT whatever the file stores;
// OpenEXR converts half/uint.
void read_rows(Imf::InputPart& in, const std::vector<std::vector<std::string>>& layers, std::vector<Image>* dst,
               int y0, int y1) {
  const Imath::Box2i dw = in.header().dataWindow();
  const Imath::Box2i rows(Imath::V2i(dw.min.x, dw.min.y + y0), Imath::V2i(dw.max.x, dw.min.y + y1 - 1));
  Imf::FrameBuffer fb;
  for (size_t l = 0; l < layers.size(); ++l) {
    Image& image = (*dst)[l];
    const size_t nc = size_t(image.channels());
    for (size_t c = 0; c < nc; ++c)
      fb.insert(layers[l][c], Imf::Slice::Make(Imf::FLOAT, image.data().data() + c, rows, sizeof(float) * nc,
                                               sizeof(float) * nc * size_t(image.width())));
  }
  in.setFrameBuffer(fb);
  in.readPixels(rows.min.y, rows.max.y);
}

// The channel groups `layers` of one part, each as one interleaved float
// image, cropped to `region` (in the part's pixels; null: all of them).
Expected<std::vector<Image>> read_part_layers(Imf::MultiPartInputFile& file, int part,
                                              const std::vector<std::vector<std::string>>& layers,
                                              const PixelRect* region, const std::string& path) {
  Imf::InputPart in(file, part);
  const Imath::Box2i dw = in.header().dataWindow();
  const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
  const int64_t height = int64_t(dw.max.y) - dw.min.y + 1;
  GDVR_RETURN_IF_ERROR(check_dimensions(path, width, height));
  const PixelRect whole = PixelRect::whole(int(width), int(height));
  const PixelRect rect = region ? *region : whole;
  if (rect.empty() || !whole.contains(rect))
    return invalid_argument(path + ": region " + rect.to_string() + " is not inside the image's " +
                            std::to_string(width) + "x" + std::to_string(height) + " pixels");
  size_t channels = 0;
  for (const std::vector<std::string>& names : layers)
    for (const std::string& name : names) {
      const Imf::Channel* ch = in.header().channels().findChannel(name);
      if (ch && (ch->xSampling != 1 || ch->ySampling != 1))
        return unimplemented(path + ": channel '" + name + "' is subsampled");
      ++channels;
    }

  std::vector<Image> out;
  for (const std::vector<std::string>& names : layers) out.emplace_back(rect.width(), rect.height(), int(names.size()));
  if (rect.x0 == 0 && rect.x1 == whole.x1) {
    read_rows(in, layers, &out, rect.y0, rect.y1);  // whole rows: straight into the result
    return out;
  }
  const size_t row_bytes = size_t(width) * std::max<size_t>(channels, 1) * sizeof(float);
  const int band = std::max(kRegionBandAlign, int(kRegionBandBytes / row_bytes) / kRegionBandAlign * kRegionBandAlign);
  std::vector<Image> staging;
  for (const std::vector<std::string>& names : layers)
    staging.emplace_back(int(width), std::min(band, rect.height()), int(names.size()));
  // Bands between multiples of `band` rows, in the order the file stores its
  // lines (OpenEXR reads any order, the written one fastest).
  std::vector<std::pair<int, int>> bands;
  for (int y0 = rect.y0; y0 < rect.y1;) {
    const int y1 = std::min(rect.y1, (y0 / band + 1) * band);
    bands.emplace_back(y0, y1);
    y0 = y1;
  }
  if (in.header().lineOrder() == Imf::DECREASING_Y) std::reverse(bands.begin(), bands.end());
  for (const auto& [y0, y1] : bands) {
    read_rows(in, layers, &staging, y0, y1);
    for (size_t l = 0; l < layers.size(); ++l)
      paste_region(staging[l], {rect.x0, 0, rect.x1, y1 - y0}, &out[l], 0, y0 - rect.y0);
  }
  return out;
}

// The named channels of one part as one interleaved float image.
Expected<Image> read_part_channels(Imf::MultiPartInputFile& file, int part,
                                   const std::vector<std::string>& names, const std::string& path) {
  auto images = read_part_layers(file, part, {names}, nullptr, path);
  if (!images.ok()) return images.status();
  return std::move(images.value().front());
}

// Luminance-chroma (Y,RY,BY) files: only RgbaInputFile knows the conversion.
// Precision is half, which is what such files store anyway.
Expected<Image> read_rgb_via_rgba(const std::string& path) {
  Imf::RgbaInputFile in(path.c_str());
  const Imath::Box2i dw = in.dataWindow();
  const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
  const int64_t height = int64_t(dw.max.y) - dw.min.y + 1;
  GDVR_RETURN_IF_ERROR(check_dimensions(path, width, height));
  std::vector<Imf::Rgba> pixels(size_t(width * height));
  in.setFrameBuffer(pixels.data() - dw.min.x - dw.min.y * width, 1, size_t(width));
  in.readPixels(dw.min.y, dw.max.y);
  Image image(int(width), int(height), 3);
  for (int64_t i = 0; i < width * height; ++i) {
    image.data()[3 * i + 0] = pixels[i].r;
    image.data()[3 * i + 1] = pixels[i].g;
    image.data()[3 * i + 2] = pixels[i].b;
  }
  return image;
}

Expected<Image> read_exr_rgb(const std::string& path) {
  Imf::MultiPartInputFile file(path.c_str());
  // The main layer is the unprefixed R,G,B of the first part that has them
  // (single-part files: part 0; multi-part: usually the "rgba" part).
  for (int p = 0; p < file.parts(); ++p) {
    const Imf::Header& h = file.header(p);
    if (is_deep(h)) continue;
    const Imf::ChannelList& cl = h.channels();
    if (cl.findChannel("R") && cl.findChannel("G") && cl.findChannel("B"))
      return read_part_channels(file, p, {"R", "G", "B"}, path);
  }
  const Imf::Header& h0 = file.header(0);
  if (!is_deep(h0)) {
    const Imf::ChannelList& cl = h0.channels();
    if (cl.findChannel("Y") && (cl.findChannel("RY") || cl.findChannel("BY")))
      return read_rgb_via_rgba(path);
    if (cl.findChannel("Y")) {
      Expected<Image> y = read_part_channels(file, 0, {"Y"}, path);
      if (!y.ok()) return y.status();
      Image rgb(y->width(), y->height(), 3);
      for (size_t i = 0; i < y->pixel_count(); ++i)
        rgb.data()[3 * i] = rgb.data()[3 * i + 1] = rgb.data()[3 * i + 2] = y->data()[i];
      return rgb;
    }
  }
  std::string available;
  for (int p = 0; p < file.parts(); ++p)
    for (auto it = file.header(p).channels().begin(); it != file.header(p).channels().end(); ++it)
      available += (available.empty() ? "" : ",") + std::string(it.name());
  return invalid_argument(path + ": no R,G,B or Y channels in the main layer (has: " + available +
                          ")");
}

// ---- PNG/JPEG via stb_image ------------------------------------------------

Expected<Image> read_stb_rgb(const std::string& path, bool raw) {
  int w = 0, h = 0, comp = 0;
  if (!stbi_info(path.c_str(), &w, &h, &comp))
    return invalid_argument(path + ": not a readable EXR, PNG or JPEG (" +
                            std::string(stbi_failure_reason()) + ")");
  // Checked before decoding: stb would otherwise try to allocate whatever the
  // header claims.
  GDVR_RETURN_IF_ERROR(check_dimensions(path, w, h));

  const bool sixteen = stbi_is_16_bit(path.c_str()) != 0;
  Image image(w, h, 3);
  auto decode = [&](auto* pixels, float max_value) -> Status {
    if (!pixels)
      return invalid_argument(path + ": cannot decode (" + std::string(stbi_failure_reason()) +
                              ")");
    // Asking stb for 3 components expands grey and drops alpha for us.
    for (size_t i = 0; i < size_t(w) * h * 3; ++i) {
      const float v = float(pixels[i]) / max_value;
      image.data()[i] = raw ? v : srgb_to_linear(v);
    }
    stbi_image_free(pixels);
    return Status::Ok();
  };
  if (sixteen) {
    GDVR_RETURN_IF_ERROR(decode(stbi_load_16(path.c_str(), &w, &h, &comp, 3), 65535.0f));
  } else {
    GDVR_RETURN_IF_ERROR(decode(stbi_load(path.c_str(), &w, &h, &comp, 3), 255.0f));
  }
  return image;
}

Status validate_layers(const std::string& path, const LayeredImage& image) {
  if (image.layers.empty()) return invalid_argument(path + ": no layers to write");
  const Image& first = image.layers.front().image;
  std::set<std::string> seen;
  for (const ImageLayer& layer : image.layers) {
    const std::string label = "layer '" + layer.name + "'";
    if (layer.image.width() != first.width() || layer.image.height() != first.height())
      return invalid_argument(path + ": " + label + " is " + std::to_string(layer.image.width()) +
                              "x" + std::to_string(layer.image.height()) + ", expected " +
                              std::to_string(first.width()) + "x" + std::to_string(first.height()));
    if (layer.image.empty()) return invalid_argument(path + ": " + label + " is empty");
    if (int(layer.channels.size()) != layer.image.channels())
      return invalid_argument(path + ": " + label + " names " +
                              std::to_string(layer.channels.size()) + " channels but has " +
                              std::to_string(layer.image.channels()));
    for (const std::string& c : layer.channels) {
      if (c.empty() || c.find('.') != std::string::npos)
        return invalid_argument(path + ": " + label + " has invalid channel name '" + c + "'");
      if (!seen.insert(full_channel_name(layer.name, c)).second)
        return invalid_argument(path + ": duplicate channel '" + full_channel_name(layer.name, c) +
                                "'");
    }
  }
  return check_dimensions(path, first.width(), first.height());
}

}  // namespace

Expected<Image> read_rgb_image(const std::string& path, bool raw) {
  if (!file_exists(path)) return not_found(path + ": no such file or not readable");
  if (!has_exr_magic(path)) return read_stb_rgb(path, raw);
  configure_openexr();
  try {
    return read_exr_rgb(path);
  } catch (const std::exception& e) {
    return invalid_argument(path + ": cannot read EXR: " + e.what());
  }
}

Expected<ExrCompression> parse_exr_compression(const std::string& name) {
  if (name == "zip") return ExrCompression::kZip;
  if (name == "zips") return ExrCompression::kZips;
  if (name == "rle") return ExrCompression::kRle;
  if (name == "piz") return ExrCompression::kPiz;
  if (name == "none") return ExrCompression::kNone;
  return invalid_argument("must be zip, zips, rle, piz or none");
}

namespace {

Imf::Compression openexr_compression(ExrCompression c) {
  switch (c) {
    case ExrCompression::kZips: return Imf::ZIPS_COMPRESSION;
    case ExrCompression::kRle: return Imf::RLE_COMPRESSION;
    case ExrCompression::kPiz: return Imf::PIZ_COMPRESSION;
    case ExrCompression::kNone: return Imf::NO_COMPRESSION;
    case ExrCompression::kZip: break;
  }
  return Imf::ZIP_COMPRESSION;
}

}  // namespace

Status write_exr(const std::string& path, const LayeredImage& image, bool half_float, ExrCompression compression) {
  GDVR_RETURN_IF_ERROR(validate_layers(path, image));
  const int width = image.layers.front().image.width();
  const int height = image.layers.front().image.height();
  const std::string tmp = temporary_path_for(path);
  configure_openexr();
  try {
    Imf::Header header(width, height);
    header.compression() = openexr_compression(compression);
    Imf::StringVector order;
    Imf::FrameBuffer fb;
    const Imf::PixelType file_type = half_float ? Imf::HALF : Imf::FLOAT;
    // OutputFile does not convert between frame-buffer and file pixel types
    // (only InputFile does), so half output needs half copies of the layers.
    std::vector<std::vector<Imath::half>> half_copies;
    if (half_float) half_copies.reserve(image.layers.size());
    for (const ImageLayer& layer : image.layers) {
      const int nc = layer.image.channels();
      char* base = nullptr;
      size_t elem = sizeof(float);
      if (half_float) {
        half_copies.emplace_back(layer.image.data().begin(), layer.image.data().end());
        base = reinterpret_cast<char*>(half_copies.back().data());
        elem = sizeof(Imath::half);
      } else {
        // Slice takes char* for reading and writing alike; OutputFile only reads.
        base = reinterpret_cast<char*>(const_cast<float*>(layer.image.data().data()));
      }
      for (int c = 0; c < nc; ++c) {
        const std::string name = full_channel_name(layer.name, layer.channels[c]);
        header.channels().insert(name, Imf::Channel(file_type));
        order.push_back(name);
        fb.insert(name, Imf::Slice(file_type, base + elem * c, elem * nc,
                                   elem * nc * size_t(width)));
      }
    }
    header.insert(kChannelOrderAttribute, Imf::StringVectorAttribute(order));
    {
      // Scoped: the file is only complete once OutputFile's destructor ran.
      Imf::OutputFile out(tmp.c_str(), header);
      out.setFrameBuffer(fb);
      out.writePixels(height);
    }
  } catch (const std::exception& e) {
    discard_temporary(tmp);
    return internal_error(path + ": cannot write EXR: " + e.what());
  }
  return commit_temporary(tmp, path);
}

namespace {

// read_exr and read_exr_region: every non-deep part's channels, grouped into
// layers, cropped to `region` (null: whole).
Expected<LayeredImage> read_exr_layers(const std::string& path, const PixelRect* region) {
  if (!file_exists(path)) return not_found(path + ": no such file or not readable");
  configure_openexr();
  try {
    Imf::MultiPartInputFile file(path.c_str());
    LayeredImage result;
    for (int p = 0; p < file.parts(); ++p) {
      const Imf::Header& h = file.header(p);
      if (is_deep(h)) continue;
      // Later parts of multi-part files conventionally carry unprefixed
      // channels with the part name acting as the layer name.
      std::string part_prefix;
      if (p > 0 && h.hasName()) part_prefix = h.name();

      std::vector<std::string> names;
      for (auto it = h.channels().begin(); it != h.channels().end(); ++it) names.push_back(it.name());
      std::map<std::string, int> written_rank;
      if (const auto* attr = h.findTypedAttribute<Imf::StringVectorAttribute>(kChannelOrderAttribute))
        for (size_t i = 0; i < attr->value().size(); ++i) written_rank[attr->value()[i]] = int(i);

      // Layers in order of the writer (or main layer first, then by name);
      // channels within a layer likewise.
      auto key = [&](const std::string& n) {
        auto it = written_rank.find(n);
        const auto [layer, channel] = split_channel_name(n);
        return std::make_tuple(it == written_rank.end() ? 1 : 0,
                               it == written_rank.end() ? 0 : it->second, !layer.empty(), layer,
                               channel_rank(channel), channel);
      };
      std::stable_sort(names.begin(), names.end(),
                       [&](const std::string& a, const std::string& b) { return key(a) < key(b); });
      std::vector<std::string> layer_order;
      std::map<std::string, std::vector<std::string>> by_layer;
      for (const std::string& n : names) {
        const std::string layer = split_channel_name(n).first;
        if (!by_layer.count(layer)) layer_order.push_back(layer);
        by_layer[layer].push_back(n);
      }
      if (layer_order.empty()) continue;  // a part without channels has nothing to read
      std::vector<std::vector<std::string>> groups;
      for (const std::string& layer : layer_order) groups.push_back(by_layer[layer]);
      auto images = read_part_layers(file, p, groups, region, path);
      if (!images.ok()) return images.status();
      for (size_t l = 0; l < layer_order.size(); ++l) {
        const std::string& layer = layer_order[l];
        std::vector<std::string> channels;
        for (const std::string& n : by_layer[layer]) channels.push_back(split_channel_name(n).second);
        std::string name = layer;
        if (!part_prefix.empty()) name = layer.empty() ? part_prefix : part_prefix + "." + layer;
        result.add(name, std::move(channels), std::move(images.value()[l]));
      }
    }
    if (result.layers.empty()) return invalid_argument(path + ": EXR has no readable channels");
    return result;
  } catch (const std::exception& e) {
    return invalid_argument(path + ": cannot read EXR: " + e.what());
  }
}

}  // namespace

Expected<LayeredImage> read_exr(const std::string& path) { return read_exr_layers(path, nullptr); }

Expected<LayeredImage> read_exr_region(const std::string& path, const PixelRect& rect) {
  return read_exr_layers(path, &rect);
}

Expected<PixelRect> read_exr_extent(const std::string& path) {
  if (!file_exists(path)) return not_found(path + ": no such file or not readable");
  configure_openexr();
  try {
    Imf::MultiPartInputFile file(path.c_str());
    for (int p = 0; p < file.parts(); ++p) {
      const Imf::Header& h = file.header(p);
      if (is_deep(h)) continue;
      const Imath::Box2i dw = h.dataWindow();
      const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
      const int64_t height = int64_t(dw.max.y) - dw.min.y + 1;
      GDVR_RETURN_IF_ERROR(check_dimensions(path, width, height));
      return PixelRect::whole(int(width), int(height));
    }
    return invalid_argument(path + ": EXR has no readable channels");
  } catch (const std::exception& e) {
    return invalid_argument(path + ": cannot read EXR: " + e.what());
  }
}

Status write_png8(const std::string& path, const Image& display_rgb) {
  const int w = display_rgb.width(), h = display_rgb.height(), nc = display_rgb.channels();
  if (display_rgb.empty() || (nc != 1 && nc < 3))
    return invalid_argument(path + ": PNG needs a non-empty 1- or 3+-channel image, got " +
                            std::to_string(nc) + " channels");
  GDVR_RETURN_IF_ERROR(check_dimensions(path, w, h));
  std::vector<uint8_t> bytes(size_t(w) * h * 3);
  for (size_t i = 0; i < display_rgb.pixel_count(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const float v = display_rgb.data()[i * nc + (nc == 1 ? 0 : c)];
      // `!(v > 0)` also catches NaN, which must not become 255 via UB casts.
      const float clamped = !(v > 0.0f) ? 0.0f : std::min(v, 1.0f);
      bytes[i * 3 + c] = uint8_t(std::lround(clamped * 255.0f));
    }
  }

  const std::string tmp = temporary_path_for(path);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(tmp.c_str(), "wb"), &std::fclose);
  if (!f) return internal_error(path + ": cannot create '" + tmp + "'");
  // Written through a callback so short writes (full disk) are detected;
  // stbi_write_png's own file handling ignores them.
  struct Sink {
    std::FILE* file;
    bool ok;
  } sink{f.get(), true};
  auto write_fn = [](void* ctx, void* data, int size) {
    auto* s = static_cast<Sink*>(ctx);
    if (std::fwrite(data, 1, size_t(size), s->file) != size_t(size)) s->ok = false;
  };
  const int encoded = stbi_write_png_to_func(write_fn, &sink, w, h, 3, bytes.data(), w * 3);
  const bool closed = std::fclose(f.release()) == 0;
  if (!encoded || !sink.ok || !closed) {
    discard_temporary(tmp);
    return internal_error(path + ": cannot write PNG");
  }
  return commit_temporary(tmp, path);
}

}  // namespace gdvr
