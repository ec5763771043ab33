// T-GPT's stage 2 by tiles (docs/tgpt.md, "Memory"): the window cache solving
// frames larger than recon.tile_size tile by tile, from frames held in memory
// or spilled to disk (SpillingFrameStore, LayerSpillFile), against the
// whole-frame windows.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "core/image/error_metrics.h"
#include "core/image/image_region.h"
#include "core/io/layer_spill_file.h"
#include "core/temporal/spilling_frame_store.h"
#include "core/temporal/temporal_window.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

// Stage-1 buffers of frame t of a noisy shot: a drifting ramp with noise in
// both passes, motion fields that fail the consistency check in a block (so
// the temporal masks reach across tile borders).
LayeredImage noisy_stage1_frame(int w, int h, int t, int n) {
  std::mt19937 rng(unsigned(1000 + t));
  std::normal_distribution<float> noise(0.0f, 0.05f);
  LayeredImage L;
  const std::vector<std::string> rgb = {"R", "G", "B"};
  auto field = [&](float base, float slope, float sigma) {
    Image im(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) im.at(x, y, c) = base + slope * float(x + 2 * t + c) + sigma * noise(rng);
    return im;
  };
  for (const char* pre : {"a_", "b_"}) {
    L.add(std::string(pre) + "primal", rgb, field(0.3f, 0.01f, 1.0f));
    L.add(std::string(pre) + "dx", rgb, field(0.01f, 0.0f, 0.3f));
    L.add(std::string(pre) + "dy", rgb, field(0.0f, 0.0f, 0.3f));
    for (const char* v : {"primal_var", "dx_var", "dy_var"}) L.add(std::string(pre) + v, rgb, field(0.0025f, 0.0f, 0.0f));
  }
  L.add("direct", rgb, Image(w, h, 3));
  Image motion(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      motion.at(x, y, 2) = 1.0f;
      if (x > w / 3 && x < w / 2 && y > h / 4 && y < h / 2) motion.at(x, y, 0) = 3.0f;  // fails the round trip
    }
  if (t + 1 < n) L.add("motion", {"X", "Y", "V"}, motion);
  if (t > 0) L.add("motion_back", {"X", "Y", "V"}, std::move(motion));
  return L;
}

constexpr int kWidth = 72, kHeight = 56, kShot = 9;

TgptSettings tiled_settings(int tile_size) {
  TgptSettings s;
  s.window = 4;
  s.recon.tile_size = tile_size;
  s.recon.tile_halo = 16;
  return s;
}

std::vector<int> shot_frames() {
  std::vector<int> frames;
  for (int f = 0; f < kShot; ++f) frames.push_back(f);
  return frames;
}

// Every frame of the shot, in order, as a streaming stage 2 asks for them.
std::vector<Image> solve_shot(TemporalWindowCache* cache, const FrameRegionReader& reader) {
  std::vector<Image> out;
  for (int f = 0; f < kShot; ++f) {
    auto img = cache->reconstruct(f, reader, nullptr);
    EXPECT_TRUE(img.ok()) << img.status().to_string();
    if (!img.ok()) return {};
    out.push_back(std::move(img.value()));
    cache->release_through(f);
  }
  return out;
}

TEST(TiledWindowTest, SpilledFramesGiveTheImagesOfFramesInMemory) {
  std::map<int, LayeredImage> held;
  const std::string dir = ::testing::TempDir();
  SpillingFrameStore spilled(dir, 0);  // every frame to disk
  for (int f = 0; f < kShot; ++f) {
    held[f] = noisy_stage1_frame(kWidth, kHeight, f, kShot);
    ASSERT_TRUE(spilled.put(f, held[f]).ok());
  }
  EXPECT_EQ(spilled.spilled_frames(), kShot);
  EXPECT_EQ(spilled.bytes_in_memory(), 0);
  TemporalWindowCache in_memory(tiled_settings(24), shot_frames()), from_disk(tiled_settings(24), shot_frames());
  const std::vector<Image> a = solve_shot(&in_memory, in_memory_region_reader(kWidth, kHeight, [&](int f) {
    return held.count(f) ? &held.at(f) : nullptr;
  }));
  const std::vector<Image> b = solve_shot(&from_disk, spilled.reader());
  ASSERT_EQ(a.size(), size_t(kShot));
  ASSERT_EQ(b.size(), size_t(kShot));
  for (int f = 0; f < kShot; ++f) EXPECT_EQ(a[size_t(f)].data(), b[size_t(f)].data()) << "frame " << f;
}

TEST(TiledWindowTest, TiledWindowsAgreeWithWholeFrameWindows) {
  std::map<int, LayeredImage> held;
  for (int f = 0; f < kShot; ++f) held[f] = noisy_stage1_frame(kWidth, kHeight, f, kShot);
  const FrameRegionReader reader =
      in_memory_region_reader(kWidth, kHeight, [&](int f) { return held.count(f) ? &held.at(f) : nullptr; });
  TemporalWindowCache tiled(tiled_settings(24), shot_frames()), whole(tiled_settings(0), shot_frames());
  const std::vector<Image> a = solve_shot(&tiled, reader), b = solve_shot(&whole, reader);
  ASSERT_EQ(a.size(), b.size());
  for (int f = 0; f < kShot; ++f) {
    auto e = rel_mse_sums(a[size_t(f)], b[size_t(f)]);
    ASSERT_TRUE(e.ok());
    EXPECT_LE(e->global(), 1e-6) << "frame " << f;
    EXPECT_GT(e->global(), 0.0) << "frame " << f << ": 3x3 tiles cannot be bit-identical to one solve";
  }
  // Each window solved once, whether by tiles or not.
  EXPECT_EQ(tiled.windows_solved(), whole.windows_solved());
}

TEST(TiledWindowTest, AFrameAskedForAgainOutOfOrderIsTheSame) {
  std::map<int, LayeredImage> held;
  for (int f = 0; f < kShot; ++f) held[f] = noisy_stage1_frame(kWidth, kHeight, f, kShot);
  const FrameRegionReader reader =
      in_memory_region_reader(kWidth, kHeight, [&](int f) { return held.count(f) ? &held.at(f) : nullptr; });
  TemporalWindowCache cache(tiled_settings(24), shot_frames());
  const std::vector<Image> in_order = solve_shot(&cache, reader);
  for (int f : {5, 2, 3}) {
    auto again = cache.reconstruct(f, reader, nullptr);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(again->data(), in_order[size_t(f)].data()) << "frame " << f;
  }
}

// ---- The spill file and the store ----

TEST(LayerSpillFileTest, RegionsReadBackAsCrops) {
  const LayeredImage frame = noisy_stage1_frame(40, 30, 1, 3);
  const std::string path = ::testing::TempDir() + "/spill_roundtrip.raw";
  ASSERT_TRUE(write_layer_spill(path, frame).ok());
  auto file = LayerSpillFile::open(path);
  ASSERT_TRUE(file.ok()) << file.status().to_string();
  EXPECT_EQ((*file)->width(), 40);
  EXPECT_EQ((*file)->height(), 30);
  for (const PixelRect& r : {PixelRect{0, 0, 40, 30}, PixelRect{7, 3, 19, 28}, PixelRect{39, 29, 40, 30}}) {
    auto got = (*file)->read(r);
    ASSERT_TRUE(got.ok()) << got.status().to_string();
    const LayeredImage want = crop_layers(frame, r);
    ASSERT_EQ(got->layers.size(), want.layers.size());
    for (size_t i = 0; i < want.layers.size(); ++i) {
      EXPECT_EQ(got->layers[i].name, want.layers[i].name);
      EXPECT_EQ(got->layers[i].channels, want.layers[i].channels);
      EXPECT_EQ(got->layers[i].image.data(), want.layers[i].image.data()) << want.layers[i].name;
    }
  }
  EXPECT_NE((*file)->read({30, 0, 41, 5}).status().message().find("not inside"), std::string::npos);
  fs::remove(path);
}

TEST(LayerSpillFileTest, CorruptOrMissingFilesAreErrorsNamingThePath) {
  const std::string path = ::testing::TempDir() + "/spill_corrupt.raw";
  std::ofstream(path) << "not a spill file at all";
  auto bad = LayerSpillFile::open(path);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find(path), std::string::npos);
  // Cut short: the header promises pixels that are not there.
  const LayeredImage frame = noisy_stage1_frame(16, 8, 0, 1);
  ASSERT_TRUE(write_layer_spill(path, frame).ok());
  fs::resize_file(path, fs::file_size(path) / 2);
  auto cut = LayerSpillFile::open(path);
  ASSERT_TRUE(cut.ok());
  EXPECT_FALSE((*cut)->read({0, 0, 16, 8}).ok());
  fs::remove(path);
  EXPECT_EQ(LayerSpillFile::open(path).status().code(), StatusCode::kNotFound);
}

TEST(SpillingFrameStoreTest, KeepsFramesInMemoryUpToTheLimit) {
  const LayeredImage frame = noisy_stage1_frame(16, 8, 0, 3);
  long long bytes = 0;
  for (const ImageLayer& l : frame.layers) bytes += (long long)l.image.data().size() * 4;
  const std::string dir = ::testing::TempDir() + "/spill_store_test";
  fs::create_directories(dir);
  {
    SpillingFrameStore store(dir, 2 * bytes);
    for (int f = 0; f < 3; ++f) ASSERT_TRUE(store.put(f, frame).ok());
    EXPECT_EQ(store.bytes_in_memory(), 2 * bytes);
    EXPECT_EQ(store.spilled_frames(), 1);
    for (int f = 0; f < 3; ++f) {
      auto whole = store.whole(f);
      ASSERT_TRUE(whole.ok() && whole.value());
      EXPECT_EQ((*whole)->layers[0].image.data(), frame.layers[0].image.data());
    }
    EXPECT_FALSE(store.whole(7).value());  // absent: null, not an error
    EXPECT_FALSE(store.put(9, noisy_stage1_frame(8, 8, 0, 1)).ok());  // another size
    store.erase(0);
    EXPECT_EQ(store.bytes_in_memory(), bytes);
    // Spill files lose their name once open: nothing to clean up, ever.
    EXPECT_TRUE(fs::is_empty(dir));
  }
  SpillingFrameStore nowhere("", 0);
  EXPECT_NE(nowhere.put(0, frame).message().find("spill folder"), std::string::npos);
}

}  // namespace
}  // namespace gdvr
