// T-GPT's sliding-window reconstruction (core/temporal/temporal_window.h):
// the Hann blend gives a frame back from exact window solutions, half
// overlapping windows' weights sum to one, errors of the solve reach the
// caller, a real solve of an exact shot reproduces it, and the schedule
// speaks the job's frame numbers.
#include "core/temporal/temporal_window.h"

#include <gtest/gtest.h>

#include <climits>
#include <map>

#include "../recon/recon_test_scene.h"

namespace gdvr {
namespace {

const std::vector<std::string> kRgb = {"R", "G", "B"};

// Stage-1 buffers of one frame whose two passes both hold `primal`, `dx`,
// `dy` (variances `var`), with zero-motion fields towards its neighbours
// (present, so each pair counts as changing and gets temporal terms).
LayeredImage pass_buffers(const Image& primal, const Image& dx, const Image& dy, float var, bool has_next,
                          bool has_prev) {
  LayeredImage L;
  Image variance(primal.width(), primal.height(), 3);
  for (float& v : variance.data()) v = var;
  for (const char* pass : {"a_", "b_"}) {
    L.add(std::string(pass) + "primal", kRgb, primal);
    L.add(std::string(pass) + "dx", kRgb, dx);
    L.add(std::string(pass) + "dy", kRgb, dy);
    for (const char* v : {"primal_var", "dx_var", "dy_var"}) L.add(std::string(pass) + v, kRgb, variance);
  }
  L.add("direct", kRgb, Image(primal.width(), primal.height(), 3));
  Image motion(primal.width(), primal.height(), 3);
  for (size_t p = 0; p < motion.data().size(); p += 3) motion.data()[p + 2] = 1.0f;  // valid, zero offset
  if (has_next) L.add("motion", {"X", "Y", "V"}, motion);
  if (has_prev) L.add("motion_back", {"X", "Y", "V"}, motion);
  return L;
}

// A 2x2 frame whose primal is its frame number.
LayeredImage tagged_buffers(int f, int n) {
  Image primal(2, 2, 3);
  for (float& v : primal.data()) v = float(f);
  return pass_buffers(primal, Image(2, 2, 3), Image(2, 2, 3), 0.01f, f + 1 < n, f > 0);
}

// The window's own primals: the blend of exact solutions must give each frame back.
Expected<ReconResult> identity_solve(const GradientWindow& w, const PixelRect&) {
  ReconResult r;
  for (const auto& f : w.frames) r.frames.push_back(f->buffer(Term::kPrimal));
  return r;
}

TEST(TemporalWindowCacheTest, BlendOfExactSolutionsGivesEachFrameBack) {
  for (int window : {1, 2, 5, 20})
    for (int hop : {0, 1, 3})
      for (int n : {1, 7, 20, 23, 61}) {
        if (hop > window) continue;
        TgptSettings settings;
        settings.window = window;
        settings.hop = hop;
        std::vector<int> frames;
        std::map<int, LayeredImage> held;
        for (int f = 0; f < n; ++f) {
          frames.push_back(f);
          held[f] = tagged_buffers(f, n);
        }
        TemporalWindowCache cache(settings, frames, identity_solve);
        for (int f : frames) {
          auto img = cache.reconstruct(f, [&](int k) { return &held.at(k); }, nullptr);
          ASSERT_TRUE(img.ok()) << img.status().to_string();
          EXPECT_NEAR(img->data()[0], float(f), 1e-4) << "W=" << window << " H=" << hop << " n=" << n;
          cache.release_through(f);
          EXPECT_LE(cache.cached_windows(), window);
        }
        // In order, every window is solved exactly once.
        EXPECT_EQ(cache.windows_solved(), int(shot_windows(n, window, hop).size()));
      }
}

TEST(TemporalWindowCacheTest, HalfOverlappingWindowsWeighFramesToOne) {
  // W = 10, H = 5 on 40 frames: windows start at 0, 5, ..., 30 (the last reaches frame 39).
  const auto windows = shot_windows(40, 10, 0);
  ASSERT_EQ(windows.size(), 7u);
  for (size_t k = 0; k < windows.size(); ++k) EXPECT_EQ(windows[k].start, int(5 * k));
  for (int f = 5; f < 10; ++f)
    EXPECT_NEAR(window_blend_weight(f, 0, 10) + window_blend_weight(f, 5, 10), 1.0, 1e-12) << f;
  EXPECT_GT(window_blend_weight(0, 0, 10), 0.0);
  // A shot shorter than W is one window.
  ASSERT_EQ(shot_windows(6, 20, 10).size(), 1u);
  EXPECT_EQ(shot_windows(6, 20, 10)[0].end, 6);
}

TEST(TemporalWindowCacheTest, SolverErrorsReachTheCaller) {
  TgptSettings bad;
  bad.window = 0;
  EXPECT_FALSE(bad.validate().ok());
  bad.window = 4;
  bad.hop = 5;
  EXPECT_FALSE(bad.validate().ok());

  TgptSettings settings;
  settings.window = 2;
  std::map<int, LayeredImage> held = {{0, tagged_buffers(0, 2)}, {1, tagged_buffers(1, 2)}};
  auto layers = [&](int k) { return &held.at(k); };
  TemporalWindowCache failing(settings, {0, 1},
                              [](const GradientWindow&, const PixelRect&) -> Expected<ReconResult> { return internal_error("boom"); });
  auto st = failing.reconstruct(0, layers, nullptr);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.status().message().find("boom"), std::string::npos);
  TemporalWindowCache short_answer(settings, {0, 1}, [](const GradientWindow&, const PixelRect&) -> Expected<ReconResult> {
    return ReconResult{};  // no frames for a window of two
  });
  EXPECT_EQ(short_answer.reconstruct(0, layers, nullptr).status().code(), StatusCode::kInternal);
  // Buffers a window needs and does not have: the frame is named.
  held.erase(1);
  TemporalWindowCache missing(settings, {0, 1});
  auto gap = missing.reconstruct(0, [&](int k) -> const LayeredImage* {
    auto it = held.find(k);
    return it == held.end() ? nullptr : &it->second;
  }, nullptr);
  ASSERT_FALSE(gap.ok());
  EXPECT_NE(gap.status().message().find("frame 1"), std::string::npos) << gap.status().message();
}

TEST(TemporalWindowCacheTest, RealSolveReproducesAnExactShot) {
  const int w = 24, h = 16, n = 9;
  // Exact finite differences, as in the reconstruction tests' scene.
  test::SceneOptions o;
  o.width = w;
  o.height = h;
  o.frames = n;
  const GradientWindow exact = test::make_window(o);
  std::map<int, LayeredImage> held;
  std::vector<int> frames;
  for (int f = 0; f < n; ++f) {
    const GradientFrame& g = *exact.frames[size_t(f)];
    held[f] = pass_buffers(g.buffer(Term::kPrimal), g.buffer(Term::kDx), g.buffer(Term::kDy), 1e-4f, f + 1 < n, f > 0);
    frames.push_back(f);
  }
  TgptSettings settings;
  settings.window = 4;
  settings.hop = 2;
  settings.motion_vectors = false;
  settings.recon.method = ReconMethod::kL2;
  settings.recon.l2_tolerance = 1e-6;
  TemporalWindowCache cache(settings, frames);
  for (int f : frames) {
    auto img = cache.reconstruct(f, [&](int k) { return &held.at(k); }, nullptr);
    ASSERT_TRUE(img.ok()) << img.status().to_string();
    EXPECT_LT(test::frame_error(img.value(), f).max, 2e-3) << f;
  }
}

// A stepped range: windows are over the job's frames in order, whatever their numbers.
TEST(TemporalWindowCacheTest, SpeaksTheJobsFrameNumbers) {
  TgptSettings settings;
  settings.window = 4;
  const std::vector<int> frames = {10, 12, 14, 16, 18, 20};
  TemporalWindowCache cache(settings, frames);
  EXPECT_EQ(cache.position(14), 2);
  EXPECT_EQ(cache.position(13), -1);
  // Windows [10, 16] and [14, 20]: frame 14 lies in both.
  EXPECT_EQ(cache.frames_needed(14), frames);
  EXPECT_EQ(cache.frames_needed(10), (std::vector<int>{10, 12, 14, 16}));
  EXPECT_EQ(cache.frames_needed(20), (std::vector<int>{14, 16, 18, 20}));
  EXPECT_EQ(cache.frames_needed(13), (std::vector<int>{13}));  // not in the shot: only itself
  // Nothing solved yet: a frame before the next one out is still read by its windows.
  EXPECT_TRUE(cache.buffers_needed(10, 12));
  EXPECT_TRUE(cache.buffers_needed(16, 12));
  // Everything out: nothing is needed.
  EXPECT_FALSE(cache.buffers_needed(20, INT_MAX));
}

}  // namespace
}  // namespace gdvr
