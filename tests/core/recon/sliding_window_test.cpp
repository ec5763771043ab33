#include "core/recon/sliding_window.h"

#include <gtest/gtest.h>

#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

// A 1x1 frame whose primal holds its frame number: lets a fake solver tag its
// output with (frame number + 1000 · window id) and the test decode blends.
std::shared_ptr<const GradientFrame> tagged_frame(int f) {
  auto fr = std::make_shared<GradientFrame>();
  fr->buffer(Term::kPrimal) = Image(1, 1, 1);
  fr->buffer(Term::kPrimal).at(0, 0, 0) = float(f);
  return fr;
}

struct Recorder {
  std::vector<std::pair<int, int>> windows;  // [first frame, size]
  WindowSolver solver() {
    return [this](const GradientWindow& w) -> Expected<std::vector<Image>> {
      windows.push_back({int(w.frames[0]->buffer(Term::kPrimal).at(0, 0, 0)), w.size()});
      std::vector<Image> out;
      for (const auto& f : w.frames) out.push_back(f->buffer(Term::kPrimal));  // identity
      return out;
    };
  }
};

void run_shot(SlidingWindowReconstructor& sw, int frames, std::vector<ReconFrame>* out, int window) {
  for (int f = 0; f < frames; ++f) {
    ASSERT_TRUE(sw.push(tagged_frame(f), out).ok());
    ASSERT_LE(sw.buffered_frames(), window);
    // Latency is bounded: everything older than one window has been emitted.
    ASSERT_GE(int(out->size()), f + 1 - window);
  }
  ASSERT_TRUE(sw.end_shot(out).ok());
}

TEST(SlidingWindowTest, EmitsEveryFrameOnceInOrderWithBoundedMemory) {
  for (int window : {1, 2, 5, 20})
    for (int hop : {0, 1, 3})
      for (int frames : {1, 7, 20, 23, 61}) {
        if (hop > window) continue;
        Recorder rec;
        SlidingWindowReconstructor sw({window, hop}, rec.solver());
        std::vector<ReconFrame> out;
        run_shot(sw, frames, &out, window);
        ASSERT_EQ(int(out.size()), frames) << window << " " << hop << " " << frames;
        for (int f = 0; f < frames; ++f) {
          EXPECT_EQ(out[f].index, f);
          // Identity solver: the normalised Hann blend must give the input back.
          EXPECT_NEAR(out[f].image.at(0, 0, 0), float(f), 1e-4);
        }
        EXPECT_LE(sw.max_buffered_frames(), window);
        // Windows are contiguous, cover the shot, and never exceed W frames.
        for (auto [start, size] : rec.windows) {
          EXPECT_LE(size, window);
          EXPECT_LE(start + size, frames);
        }
        EXPECT_EQ(rec.windows.back().first + rec.windows.back().second, frames);
      }
}

TEST(SlidingWindowTest, FiftyPercentOverlapSolvesEachFrameTwice) {
  Recorder rec;
  SlidingWindowReconstructor sw({/* window = */ 10, /* hop = */ 0}, rec.solver());
  std::vector<ReconFrame> out;
  run_shot(sw, 40, &out, 10);
  // Starts 0, 5, ..., 30 (the last reaches frame 39).
  ASSERT_EQ(rec.windows.size(), 7u);
  for (size_t k = 0; k < rec.windows.size(); ++k) EXPECT_EQ(rec.windows[k].first, int(5 * k));
  // Hann weights of two half-overlapping windows sum to one.
  for (int f = 5; f < 10; ++f)
    EXPECT_NEAR(SlidingWindowReconstructor::hann_weight(f, 0, 10) + SlidingWindowReconstructor::hann_weight(f, 5, 10),
                1.0, 1e-12);
  EXPECT_GT(SlidingWindowReconstructor::hann_weight(0, 0, 10), 0.0);
}

TEST(SlidingWindowTest, ShotShorterThanWindowIsOneWindowAndShotsRestart) {
  Recorder rec;
  SlidingWindowReconstructor sw({20, 10}, rec.solver());
  std::vector<ReconFrame> out;
  run_shot(sw, 6, &out, 20);
  ASSERT_EQ(rec.windows.size(), 1u);
  EXPECT_EQ(rec.windows[0], std::make_pair(0, 6));
  out.clear();
  run_shot(sw, 3, &out, 20);  // next shot: numbering restarts, no window spans the cut
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].index, 0);
  EXPECT_EQ(rec.windows.back(), std::make_pair(0, 3));
}

TEST(SlidingWindowTest, RejectsBadOptionsAndPropagatesSolverErrors) {
  EXPECT_FALSE(SlidingWindowOptions({0, 0}).validate().ok());
  EXPECT_FALSE(SlidingWindowOptions({4, 5}).validate().ok());
  ReconSettings bad;
  bad.alpha = -1;
  EXPECT_FALSE(SlidingWindowReconstructor::create({4, 2}, bad).ok());
  SlidingWindowReconstructor sw({2, 1}, [](const GradientWindow&) -> Expected<std::vector<Image>> {
    return internal_error("boom");
  });
  std::vector<ReconFrame> out;
  ASSERT_TRUE(sw.push(tagged_frame(0), &out).ok());
  const Status st = sw.push(tagged_frame(1), &out);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("boom"), std::string::npos);
}

TEST(SlidingWindowTest, RealSolverReproducesExactSequence) {
  test::SceneOptions o;
  o.width = 24;
  o.height = 16;
  o.frames = 9;
  o.temporal = true;
  GradientWindow all = test::make_window(o);
  ReconSettings s;
  s.l2_tolerance = 1e-6;
  auto sw = SlidingWindowReconstructor::create({4, 2}, s);
  ASSERT_TRUE(sw.ok());
  std::vector<ReconFrame> out;
  for (const auto& f : all.frames) ASSERT_TRUE(sw->push(f, &out).ok());
  ASSERT_TRUE(sw->end_shot(&out).ok());
  ASSERT_EQ(out.size(), 9u);
  for (int f = 0; f < 9; ++f) EXPECT_LT(test::frame_error(out[f].image, f).max, 2e-3) << f;
}

}  // namespace
}  // namespace gdvr
