// The sliding-window schedule of stage 2: windows as frames stream in, frames
// in order with bounded latency, and buffers bounded by the window whatever
// the shot length.
#include "core/temporal/stream_schedule.h"

#include <gtest/gtest.h>

#include <map>

#include "core/temporal/temporal_window.h"

namespace gdvr {
namespace {

// The windows a streaming solver forms: the first W frames, then every H
// frames the W frames from there while a whole window fits, then what is
// left after the last whole window as one clamped window.
TEST(TemporalWindowTest, WindowsAreThoseOfAStreamingSolver) {
  for (int n : {1, 2, 5, 19, 20, 21, 30, 45, 64})
    for (int w : {1, 2, 3, 4, 20}) {
      const int hop = std::max(1, w / 2);
      std::vector<std::pair<int, int>> expected;
      int start = 0, end = 0;
      for (; start + w <= n; start += hop) expected.push_back({start, end = start + w});
      if (end < n) expected.push_back({start, n});
      std::vector<std::pair<int, int>> ours;
      for (const WindowRange& wr : shot_windows(n, w, 0)) ours.push_back({wr.start, wr.end});
      EXPECT_EQ(ours, expected) << "n=" << n << " W=" << w;
      // They cover the shot, start in order, and hold at most W frames.
      EXPECT_EQ(ours.front().first, 0);
      EXPECT_EQ(ours.back().second, n);
      for (size_t k = 0; k < ours.size(); ++k) {
        EXPECT_LE(ours[k].second - ours[k].first, w);
        if (k > 0) {
          EXPECT_GT(ours[k].first, ours[k - 1].first);
          EXPECT_LE(ours[k].first, ours[k - 1].second);
        }
      }
    }
}

// Streams a shot through StreamSchedule exactly as run_job does.
struct StreamRun {
  std::vector<int> order;
  int max_latency = 0;  // frames rendered beyond f when f came out
  int max_buffered = 0;
};

StreamRun stream(int n, int w) {
  std::vector<int> todo;
  for (int f = 0; f < n; ++f) todo.push_back(f);
  TgptSettings settings;
  settings.window = w;
  const TemporalWindowCache windows(settings, todo);
  std::vector<std::vector<int>> needs;
  for (int f : todo) needs.push_back(windows.frames_needed(f));
  StreamSchedule s(todo, needs);
  StreamRun run;
  int rendered = 0;
  for (int f : s.render_order()) {
    s.rendered(f);
    ++rendered;
    for (int r = s.ready(); r >= 0; r = s.ready()) {
      run.order.push_back(r);
      run.max_latency = std::max(run.max_latency, rendered - 1 - r);
      s.finalized();
    }
    s.releasable();
  }
  run.max_buffered = s.max_buffered();
  return run;
}

TEST(TemporalWindowTest, FramesStreamInOrderWithBoundedBuffers) {
  for (int w : {1, 2, 4, 20}) {
    const int hop = std::max(1, w / 2);
    StreamRun a = stream(100, w), b = stream(300, w);
    ASSERT_EQ(a.order.size(), 100u);
    for (int i = 0; i < 100; ++i) ASSERT_EQ(a.order[size_t(i)], i);
    // A frame waits at most for the rest of the last window containing it (and its successor).
    EXPECT_LE(a.max_latency, std::max(1, w));
    // Buffers: the windows of the next frame out plus the frame in flight; same for a 3x longer shot.
    EXPECT_LE(a.max_buffered, w + hop + 1) << w;
    EXPECT_EQ(a.max_buffered, b.max_buffered) << w;
  }
}

// A tiny frame with every layer stage 2 reads (a moving ramp plus a fixed pattern).
LayeredImage tiny_frame(int t, int n) {
  const int w = 4, h = 4;
  LayeredImage L;
  const std::vector<std::string> rgb = {"R", "G", "B"};
  auto img = [&](float base) {
    Image im(w, h, 3);
    for (size_t k = 0; k < im.data().size(); ++k) im.data()[k] = base + 0.01f * float(k % 7);
    return im;
  };
  for (const char* pre : {"a_", "b_"}) {
    L.add(std::string(pre) + "primal", rgb, img(0.5f + 0.01f * t));
    L.add(std::string(pre) + "dx", rgb, img(0.0f));
    L.add(std::string(pre) + "dy", rgb, img(0.0f));
    for (const char* v : {"primal_var", "dx_var", "dy_var"}) L.add(std::string(pre) + v, rgb, img(0.001f));
  }
  L.add("direct", rgb, Image(w, h, 3));
  Image motion(w, h, 3);
  for (int k = 0; k < w * h; ++k) motion.data()[size_t(k) * 3 + 2] = 1.0f;
  if (t + 1 < n) L.add("motion", {"X", "Y", "V"}, motion);
  if (t > 0) L.add("motion_back", {"X", "Y", "V"}, motion);
  return L;
}

// run_job's tgpt loop with real window solves: with the cache's finer release
// rule about W frames of buffers are held, the same for a 2x longer shot.
int stream_with_cache(int n, int w, std::vector<int>* order) {
  std::vector<int> todo;
  for (int f = 0; f < n; ++f) todo.push_back(f);
  TgptSettings settings;
  settings.window = w;
  TemporalWindowCache cache(settings, todo);
  std::vector<std::vector<int>> needs;
  for (int f : todo) needs.push_back(cache.frames_needed(f));
  StreamSchedule s(todo, needs);
  std::map<int, LayeredImage> held;
  for (int f : s.render_order()) {
    held[f] = tiny_frame(f, n);
    s.rendered(f);
    for (int r = s.ready(); r >= 0; r = s.ready()) {
      auto img = cache.reconstruct(r, [&](int p) -> const LayeredImage* {
        auto it = held.find(p);
        return it == held.end() ? nullptr : &it->second;
      }, nullptr);
      EXPECT_TRUE(img.ok()) << img.status().to_string();
      if (!img.ok()) return -1;
      order->push_back(r);
      s.finalized();
      cache.release_through(r);
    }
    const int next_out = s.done() ? n : todo[size_t(s.next_index())];
    for (int d : s.releasable([&](int f) { return cache.buffers_needed(f, next_out); })) held.erase(d);
    EXPECT_LE(cache.cached_windows(), 3);
  }
  return s.max_buffered();
}

TEST(TemporalWindowTest, SolvedWindowsReleaseTheirBuffers) {
  for (int w : {2, 4, 8}) {
    std::vector<int> a, b;
    const int held_a = stream_with_cache(24, w, &a), held_b = stream_with_cache(48, w, &b);
    ASSERT_EQ(a.size(), 24u);
    for (int i = 0; i < 24; ++i) ASSERT_EQ(a[size_t(i)], i);
    EXPECT_LE(held_a, w + 1) << w;
    EXPECT_EQ(held_a, held_b) << w;
  }
}

TEST(TemporalWindowTest, ShortShotsAreOneWindow) {
  EXPECT_EQ(shot_windows(2, 20, 0).size(), 1u);
  EXPECT_EQ(shot_windows(2, 20, 0)[0].end, 2);
  auto need = positions_needed(2, 20, 0, 0);
  EXPECT_EQ(need, (std::vector<int>{0, 1}));
  EXPECT_EQ(positions_needed(5, 1, 0, 4), (std::vector<int>{4}));
  EXPECT_EQ(positions_needed(5, 1, 0, 2), (std::vector<int>{2, 3}));
}

}  // namespace
}  // namespace gdvr
