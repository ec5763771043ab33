// CameraHitCache: every entry is the first hit trace_camera_hit gives for the
// pixel's ray at the shared sub-pixel position, tile pixels and ring pixels
// alike; each entry is traced once per sample index (counted once), and
// begin() forgets the previous index's hits.
#include "core/gradient/camera_hit_cache.h"

#include <gtest/gtest.h>

#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

bool same(Vec3f a, Vec3f b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Bit-identical: the cache must not change what the path code sees.
void expect_same_hit(const CameraHit& a, const CameraHit& b, int x, int y) {
  EXPECT_TRUE(same(a.ray.o, b.ray.o) && same(a.ray.d, b.ray.d)) << x << "," << y;
  ASSERT_EQ(a.hit, b.hit) << x << "," << y;
  if (!a.hit) return;
  EXPECT_TRUE(same(a.si.p, b.si.p) && same(a.si.wi, b.si.wi) && same(a.si.sh_frame.n, b.si.sh_frame.n))
      << x << "," << y;
  EXPECT_EQ(a.si.t, b.si.t) << x << "," << y;
  EXPECT_EQ(a.si.shape, b.si.shape) << x << "," << y;
  EXPECT_EQ(a.si.prim, b.si.prim) << x << "," << y;
}

TEST(CameraHitCacheTest, EntriesAreTheRaysFirstHitsTracedOncePerSampleIndex) {
  auto ts = test::load_test_scene("cbox", 16, 16);
  ASSERT_TRUE(ts);
  PerspectiveCamera camera(ts->scene->scene().camera, 16, 16);
  CameraHitCache cache(*ts->scene, camera);
  const Tile tile{4, 4, 12, 10};
  for (Vec2f jitter : {Vec2f(0.25f, 0.75f), Vec2f(0.9f, 0.1f)}) {
    PathCounters counters;
    cache.begin(tile, jitter, counters);
    // The tile's own pixels are traced up front, as streams.
    int traced = (tile.x1 - tile.x0) * (tile.y1 - tile.y0);
    EXPECT_EQ(counters.rays, uint64_t(traced));
    // The tile and its ring (corners excluded: offsets go left, right, up, down).
    for (int y = tile.y0 - 1; y <= tile.y1; ++y)
      for (int x = tile.x0 - 1; x <= tile.x1; ++x) {
        const bool ring_x = x < tile.x0 || x >= tile.x1, ring_y = y < tile.y0 || y >= tile.y1;
        if (ring_x && ring_y) continue;
        PathCounters own;
        const CameraHit expected =
            trace_camera_hit(*ts->scene, camera.generate_ray({float(x) + jitter.x, float(y) + jitter.y}), own);
        expect_same_hit(cache.at(x, y, counters), expected, x, y);
        if (ring_x || ring_y) {
          ++traced;
          EXPECT_EQ(counters.rays, uint64_t(traced)) << "a ring pixel's first lookup traces one ray";
        } else {
          EXPECT_EQ(counters.rays, uint64_t(traced)) << "a tile pixel's lookup traces none";
        }
        expect_same_hit(cache.at(x, y, counters), expected, x, y);
        EXPECT_EQ(counters.rays, uint64_t(traced)) << "second lookup traces none";
      }
  }
}

}  // namespace
}  // namespace gdvr
