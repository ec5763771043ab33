#include "core/io/image_io.h"
#include "core/image/image_region.h"
#include "core/io/atomic_file.h"
#include "core/io/exr_region_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace gdvr {
namespace {

// Per-process scratch names so concurrent test runs of other engineers in the
// shared tree never collide.
std::string scratch(const std::string& name) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir ? dir : "/tmp") + "/gdvr_io_" + std::to_string(::getpid()) + "_" + name;
}

Image ramp(int w, int h, int nc, float offset) {
  Image img(w, h, nc);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < nc; ++c) img.at(x, y, c) = offset + 0.37f * x - 1.25f * y + 10.0f * c;
  return img;
}

bool file_exists(const std::string& path) {
  std::ifstream f(path);
  return f.good();
}

// Every codec a job may pick is lossless: the same bits come back, and the
// codec is the one asked for (the files differ in size).
TEST(ExrRoundTrip, EveryCodecGivesTheSameBitsBack) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(19, 37, 3, 0.5f));  // > 16 lines: several ZIP blocks
  Image noisy = ramp(19, 37, 3, -3.0f);
  uint32_t state = 12345;
  for (float& v : noisy.data()) {
    state = state * 1664525u + 1013904223u;
    v += float(state >> 8) * 0x1p-24f;  // mantissa noise, as sampled gradients have
  }
  img.add("dx", {"R", "G", "B"}, noisy);
  Image flat(19, 37, 1);
  for (float& v : flat.data()) v = 0.25f;  // runs: every codec shrinks it
  img.add("flat", {"Y"}, flat);
  std::vector<uintmax_t> sizes;
  for (const char* name : {"zip", "zips", "rle", "piz", "none"}) {
    Expected<ExrCompression> codec = parse_exr_compression(name);
    ASSERT_TRUE(codec.ok()) << name;
    const std::string path = scratch(std::string("codec_") + name + ".exr");
    ASSERT_TRUE(write_exr(path, img, /* half_float = */ false, *codec).ok()) << name;
    std::ifstream f(path, std::ios::binary | std::ios::ate);
    sizes.push_back(uintmax_t(f.tellg()));
    Expected<LayeredImage> back = read_exr(path);
    ASSERT_TRUE(back.ok()) << name << ": " << back.status().to_string();
    ASSERT_EQ(back->layers.size(), img.layers.size());
    for (size_t i = 0; i < img.layers.size(); ++i)
      EXPECT_EQ(back->layers[i].image.data(), img.layers[i].image.data()) << name << " layer " << i;
    std::remove(path.c_str());
  }
  // Each codec was the one asked for: every one shrinks the file, each to its own size.
  for (size_t i = 0; i + 1 < sizes.size(); ++i) {
    EXPECT_LT(sizes[i], sizes.back()) << "codec " << i << " wrote the uncompressed file";
    for (size_t j = i + 1; j + 1 < sizes.size(); ++j) EXPECT_NE(sizes[i], sizes[j]) << i << " and " << j;
  }
  EXPECT_FALSE(parse_exr_compression("dwaa").ok());  // lossy: not offered
  EXPECT_FALSE(parse_exr_compression("ZIP").ok());
}

TEST(ExrRoundTrip, MultiLayerOddSizeFloatIsExact) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(7, 5, 3, 0.5f));
  img.add("dx", {"R", "G", "B"}, ramp(7, 5, 3, -3.0f));
  img.add("variance", {"Y"}, ramp(7, 5, 1, 100.0f));
  img.add("albedo", {"Z", "A"}, ramp(7, 5, 2, 7.0f));  // deliberately non-sorted
  const std::string path = scratch("roundtrip.exr");
  ASSERT_TRUE(write_exr(path, img).ok());
  EXPECT_FALSE(file_exists(temporary_path_for(path)));

  Expected<LayeredImage> back = read_exr(path);
  ASSERT_TRUE(back.ok()) << back.status().to_string();
  ASSERT_EQ(back->layers.size(), img.layers.size());
  for (size_t i = 0; i < img.layers.size(); ++i) {
    const ImageLayer& a = img.layers[i];
    const ImageLayer& b = back->layers[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.channels, b.channels);
    ASSERT_EQ(b.image.width(), 7);
    ASSERT_EQ(b.image.height(), 5);
    EXPECT_EQ(a.image.data(), b.image.data()) << "layer " << a.name;
  }

  Expected<Image> rgb = read_rgb_image(path);
  ASSERT_TRUE(rgb.ok()) << rgb.status().to_string();
  EXPECT_EQ(rgb->data(), img.layers[0].image.data());
  std::remove(path.c_str());
}

// EXR's standard depth channel is a bare "Z" beside R,G,B: gdvr writes its
// depth layer (named "Z", one channel "Z") so, and reads such a channel back
// as that layer, not as a fourth colour channel of the main image.
TEST(ExrRoundTrip, DepthLayerIsTheBareZChannel) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(6, 4, 3, 0.5f));
  img.add("N", {"X", "Y", "Z"}, ramp(6, 4, 3, -1.0f));
  img.add("Z", {"Z"}, ramp(6, 4, 1, 5.0f));
  const std::string path = scratch("depth.exr");
  ASSERT_TRUE(write_exr(path, img).ok());
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The channel list holds each name NUL-terminated, after the previous
  // entry's sampling rate (1): "...\1\0\0\0Z\0".
  EXPECT_NE(bytes.find(std::string("\1\0\0\0Z\0", 6)), std::string::npos);
  EXPECT_EQ(bytes.find(std::string("Z.Z\0", 4)), std::string::npos);
  EXPECT_NE(bytes.find(std::string("N.Z\0", 4)), std::string::npos);

  Expected<LayeredImage> back = read_exr(path);
  ASSERT_TRUE(back.ok()) << back.status().to_string();
  ASSERT_EQ(back->layers.size(), 3u);
  EXPECT_EQ(back->find("")->channels, (std::vector<std::string>{"R", "G", "B"}));
  ASSERT_NE(back->find("Z"), nullptr);
  EXPECT_EQ(back->find("Z")->channels, (std::vector<std::string>{"Z"}));
  EXPECT_EQ(back->find("Z")->image.data(), img.layers[2].image.data());
  // A layer "Z" beside a main image that has a channel "Z" names it twice.
  LayeredImage twice;
  twice.add("", {"R", "G", "Z"}, ramp(6, 4, 3, 0.5f));
  twice.add("Z", {"Z"}, ramp(6, 4, 1, 5.0f));
  EXPECT_EQ(write_exr(path, twice).code(), StatusCode::kInvalidArgument);
  std::remove(path.c_str());
}

TEST(ExrRoundTrip, HalfFloatWithinHalfPrecision) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(9, 3, 3, 0.25f));
  const std::string path = scratch("half.exr");
  const Status st = write_exr(path, img, /* half_float = */ true);
  ASSERT_TRUE(st.ok()) << st.to_string();
  Expected<LayeredImage> back = read_exr(path);
  ASSERT_TRUE(back.ok()) << back.status().to_string();
  const auto& a = img.layers[0].image.data();
  const auto& b = back->layers[0].image.data();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], std::abs(a[i]) * 1e-3f + 1e-4f);
  std::remove(path.c_str());
}

TEST(ExrWrite, RejectsMismatchedLayers) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, Image(4, 4, 3));
  img.add("dx", {"R", "G", "B"}, Image(5, 4, 3));
  const Status st = write_exr(scratch("bad.exr"), img);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("dx"), std::string::npos) << st.message();

  LayeredImage wrong_channels;
  wrong_channels.add("", {"R", "G"}, Image(4, 4, 3));
  EXPECT_FALSE(write_exr(scratch("bad2.exr"), wrong_channels).ok());
  EXPECT_FALSE(write_exr(scratch("bad3.exr"), LayeredImage{}).ok());
}

TEST(ExrRead, BundledReferences) {
  const std::string dir = std::string(GDVR_SOURCE_DIR) + "/scenes/references/";
  struct Ref {
    const char* file;
    int width, height;
  };
  const Ref refs[] = {{"cbox_256_box_4096spp.exr", 256, 256},
                      {"cornell-box_256_box_4096spp.exr", 256, 256},
                      {"matpreview_256x192_box_4096spp.exr", 256, 192},
                      {"veach-mis_320x180_box_4096spp.exr", 320, 180}};
  for (const Ref& r : refs) {
    Expected<Image> img = read_rgb_image(dir + r.file);
    ASSERT_TRUE(img.ok()) << img.status().to_string();
    EXPECT_EQ(img->width(), r.width) << r.file;
    EXPECT_EQ(img->height(), r.height) << r.file;
    EXPECT_EQ(img->channels(), 3);
    double sum = 0;
    for (float v : img->data()) {
      ASSERT_TRUE(std::isfinite(v)) << r.file;
      sum += v;
    }
    const double mean = sum / double(img->data().size());
    // Lit interiors rendered at unit exposure: neither black nor blown out.
    EXPECT_GT(mean, 0.005) << r.file;
    EXPECT_LT(mean, 20.0) << r.file;
  }
}

TEST(ExrRead, TruncatedAndCorruptFilesGiveErrors) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(64, 48, 3, 1.0f));
  const std::string good = scratch("good.exr");
  ASSERT_TRUE(write_exr(good, img).ok());
  std::ifstream in(good, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  ASSERT_GT(bytes.size(), 400u);

  const std::string truncated = scratch("truncated.exr");
  std::ofstream(truncated, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() / 2));
  Expected<Image> t = read_rgb_image(truncated);
  ASSERT_FALSE(t.ok());
  EXPECT_NE(t.status().message().find(truncated), std::string::npos) << t.status().message();
  EXPECT_FALSE(read_exr(truncated).ok());

  // Header intact, body garbage: exercises the decompressor's error paths.
  std::vector<char> garbled = bytes;
  for (size_t i = 300; i < garbled.size(); ++i) garbled[i] = char(i * 131 + 7);
  const std::string corrupt = scratch("corrupt.exr");
  std::ofstream(corrupt, std::ios::binary).write(garbled.data(), std::streamsize(garbled.size()));
  EXPECT_FALSE(read_rgb_image(corrupt).ok());
  EXPECT_FALSE(read_exr(corrupt).ok());

  // Only the magic number.
  const std::string magic_only = scratch("magic.exr");
  std::ofstream(magic_only, std::ios::binary).write(bytes.data(), 4);
  EXPECT_FALSE(read_rgb_image(magic_only).ok());

  for (const auto& p : {good, truncated, corrupt, magic_only}) std::remove(p.c_str());
}

TEST(ExrRead, MutatedFilesNeverCrash) {
  // Cheap deterministic fuzzing: single-byte corruptions across the header
  // and offset table, where OpenEXR trusts sizes and offsets most.
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(13, 11, 3, 1.0f));
  img.add("dx", {"Y"}, ramp(13, 11, 1, 2.0f));
  const std::string good = scratch("fuzz_src.exr");
  ASSERT_TRUE(write_exr(good, img).ok());
  std::ifstream in(good, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string mutated = scratch("fuzz.exr");
  uint32_t state = 12345;
  int failures = 0;
  for (int trial = 0; trial < 100; ++trial) {
    state = state * 1664525u + 1013904223u;
    std::vector<char> m = bytes;
    const size_t pos = 4 + (state >> 8) % std::min<size_t>(m.size() - 4, 600);
    m[pos] = char(state >> 24);
    std::ofstream(mutated, std::ios::binary | std::ios::trunc).write(m.data(), std::streamsize(m.size()));
    Expected<LayeredImage> r = read_exr(mutated);
    Expected<Image> rgb = read_rgb_image(mutated);
    failures += !r.ok() + !rgb.ok();
  }
  EXPECT_GT(failures, 0);  // some mutations must have been detected
  std::remove(good.c_str());
  std::remove(mutated.c_str());
}

// Region reads (a farm tile task's view of a frame's buffers) give exactly
// the crop of a whole read. 40 channels of 320 pixels are 51 KB a row, so a
// region read whose columns are cropped stages bands of 64 rows: the rects
// below cross band borders, span three bands, and touch every edge.
TEST(ExrRegion, EqualsCropOfWholeRead) {
  LayeredImage img;
  for (int l = 0; l < 10; ++l)
    img.add(l == 0 ? "" : "layer" + std::to_string(l), {"R", "G", "B", "A"}, ramp(320, 200, 4, float(l) * 7.5f));
  const std::string path = scratch("region.exr");
  ASSERT_TRUE(write_exr(path, img).ok());
  Expected<LayeredImage> whole = read_exr(path);
  ASSERT_TRUE(whole.ok()) << whole.status().to_string();

  Expected<PixelRect> extent = read_exr_extent(path);
  ASSERT_TRUE(extent.ok()) << extent.status().to_string();
  EXPECT_EQ(extent.value(), PixelRect::whole(320, 200));

  const PixelRect rects[] = {
      PixelRect::whole(320, 200),  // the full frame
      {0, 0, 320, 1},              // first row
      {0, 199, 320, 200},          // last row
      {0, 50, 320, 150},           // whole rows: read straight into the result
      {5, 60, 300, 70},            // across the band border at row 64
      {100, 63, 200, 129},         // three bands
      {0, 0, 1, 200},              // first column
      {319, 0, 320, 200},          // last column
      {310, 190, 320, 200},        // bottom-right corner
      {17, 130, 18, 131},          // one pixel
  };
  for (const PixelRect& r : rects) {
    Expected<LayeredImage> region = read_exr_region(path, r);
    ASSERT_TRUE(region.ok()) << r.to_string() << ": " << region.status().to_string();
    const LayeredImage crop = crop_layers(whole.value(), r);
    ASSERT_EQ(region->layers.size(), crop.layers.size()) << r.to_string();
    for (size_t l = 0; l < crop.layers.size(); ++l) {
      EXPECT_EQ(region->layers[l].name, crop.layers[l].name);
      EXPECT_EQ(region->layers[l].channels, crop.layers[l].channels);
      ASSERT_EQ(region->layers[l].image.width(), r.width());
      ASSERT_EQ(region->layers[l].image.height(), r.height());
      EXPECT_EQ(region->layers[l].image.data(), crop.layers[l].image.data()) << r.to_string() << " layer " << l;
    }
  }

  // The same through ExrRegionFile, as the farm's tile tasks read buffers.
  auto file = ExrRegionFile::open(path);
  ASSERT_TRUE(file.ok()) << file.status().to_string();
  EXPECT_EQ((*file)->width(), 320);
  EXPECT_EQ((*file)->height(), 200);
  auto via_file = (*file)->read({5, 60, 300, 70});
  ASSERT_TRUE(via_file.ok());
  EXPECT_EQ(via_file->layers[3].image.data(), crop_image(whole->layers[3].image, {5, 60, 300, 70}).data());
  std::remove(path.c_str());
}

TEST(ExrRegion, HalfFloatFileEqualsCrop) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(33, 21, 3, 0.25f));
  img.add("Z", {"Z"}, ramp(33, 21, 1, 2.0f));
  const std::string path = scratch("region_half.exr");
  ASSERT_TRUE(write_exr(path, img, /* half_float = */ true).ok());
  Expected<LayeredImage> whole = read_exr(path);
  ASSERT_TRUE(whole.ok());
  const PixelRect r{3, 4, 30, 20};
  Expected<LayeredImage> region = read_exr_region(path, r);
  ASSERT_TRUE(region.ok()) << region.status().to_string();
  ASSERT_EQ(region->layers.size(), 2u);
  for (size_t l = 0; l < 2; ++l)
    EXPECT_EQ(region->layers[l].image.data(), crop_image(whole->layers[l].image, r).data());
  std::remove(path.c_str());
}

TEST(ExrRegion, BadRectsAndFilesAreErrors) {
  LayeredImage img;
  img.add("", {"R", "G", "B"}, ramp(64, 48, 3, 1.0f));
  const std::string path = scratch("region_bad.exr");
  ASSERT_TRUE(write_exr(path, img).ok());
  const PixelRect bad[] = {{5, 5, 5, 10}, {0, 0, 65, 10}, {-1, 0, 10, 10}, {0, 40, 10, 49}, {10, 10, 5, 20}};
  for (const PixelRect& r : bad) {
    Expected<LayeredImage> region = read_exr_region(path, r);
    ASSERT_FALSE(region.ok()) << r.to_string();
    EXPECT_EQ(region.status().code(), StatusCode::kInvalidArgument) << r.to_string();
    EXPECT_NE(region.status().message().find(path), std::string::npos) << region.status().message();
    EXPECT_NE(region.status().message().find(r.to_string()), std::string::npos) << region.status().message();
  }

  EXPECT_EQ(read_exr_region(scratch("region_missing.exr"), {0, 0, 1, 1}).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(read_exr_extent(scratch("region_missing.exr")).status().code(), StatusCode::kNotFound);
  EXPECT_FALSE(ExrRegionFile::open(scratch("region_missing.exr")).ok());

  // A file cut short: the rows still there read, the rows lost are an error
  // naming the file, never a crash.
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string truncated = scratch("region_truncated.exr");
  std::ofstream(truncated, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() * 3 / 4));
  ASSERT_TRUE(read_exr_extent(truncated).ok());
  Expected<LayeredImage> cut = read_exr_region(truncated, {0, 40, 64, 48});
  ASSERT_FALSE(cut.ok());
  EXPECT_NE(cut.status().message().find(truncated), std::string::npos) << cut.status().message();
  std::remove(path.c_str());
  std::remove(truncated.c_str());
}

TEST(ImageIo, MissingFileIsNotFound) {
  Expected<Image> img = read_rgb_image(scratch("does_not_exist.png"));
  ASSERT_FALSE(img.ok());
  EXPECT_EQ(img.status().code(), StatusCode::kNotFound);
  EXPECT_NE(img.status().message().find("does_not_exist.png"), std::string::npos);
  EXPECT_EQ(read_exr(scratch("nope.exr")).status().code(), StatusCode::kNotFound);
}

TEST(ImageIo, GarbageFileIsInvalidArgument) {
  const std::string path = scratch("garbage.png");
  std::ofstream(path) << "this is not an image";
  Expected<Image> img = read_rgb_image(path);
  ASSERT_FALSE(img.ok());
  EXPECT_EQ(img.status().code(), StatusCode::kInvalidArgument);
  std::remove(path.c_str());
}

TEST(PngRoundTrip, WriteThenReadRawAndLinear) {
  Image img(5, 3, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) img.set_rgb(x, y, {x / 4.0f, y / 2.0f, 0.5f});
  img.at(0, 0, 0) = std::nanf("");  // must not crash or turn white
  img.at(1, 0, 0) = 7.0f;           // clamps
  const std::string path = scratch("roundtrip.png");
  ASSERT_TRUE(write_png8(path, img).ok());

  Expected<Image> raw = read_rgb_image(path, /* raw = */ true);
  ASSERT_TRUE(raw.ok()) << raw.status().to_string();
  ASSERT_EQ(raw->width(), 5);
  ASSERT_EQ(raw->height(), 3);
  EXPECT_EQ(raw->at(0, 0, 0), 0.0f);
  EXPECT_EQ(raw->at(1, 0, 0), 1.0f);
  for (int y = 0; y < 3; ++y)
    for (int x = 2; x < 5; ++x)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(raw->at(x, y, c), img.at(x, y, c), 0.5f / 255.0f + 1e-6f);

  Expected<Image> lin = read_rgb_image(path);
  ASSERT_TRUE(lin.ok());
  // 128/255 encoded sRGB is ~0.2158 linear.
  EXPECT_NEAR(lin->at(2, 0, 2), 0.2158f, 2e-3f);

  EXPECT_FALSE(write_png8(scratch("empty.png"), Image()).ok());
  std::remove(path.c_str());
}

TEST(PngRoundTrip, GreyImageExpandsToRgb) {
  Image grey(4, 2, 1);
  for (size_t i = 0; i < grey.data().size(); ++i) grey.data()[i] = float(i) / 7.0f;
  const std::string path = scratch("grey.png");
  ASSERT_TRUE(write_png8(path, grey).ok());
  Expected<Image> back = read_rgb_image(path, /* raw = */ true);
  ASSERT_TRUE(back.ok());
  ASSERT_EQ(back->channels(), 3);
  EXPECT_EQ(back->at(3, 1, 0), back->at(3, 1, 2));
  EXPECT_NEAR(back->at(3, 1, 1), 1.0f, 1e-6f);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace gdvr
