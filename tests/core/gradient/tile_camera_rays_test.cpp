// TileCameraRays: every entry is the first hit trace_camera_hit gives for its
// ray (the base ray at the pixel's own position, the offsets' at the same
// position moved into each neighbour), bit for bit; each ray is traced once,
// and offsets into neighbours outside the image are not traced.
#include "core/gradient/tile_camera_rays.h"

#include <gtest/gtest.h>

#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

bool same(Vec3f a, Vec3f b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

void expect_same_hit(const CameraHit& a, const CameraHit& b, const std::string& where) {
  EXPECT_TRUE(same(a.ray.o, b.ray.o) && same(a.ray.d, b.ray.d)) << where;
  ASSERT_EQ(a.hit, b.hit) << where;
  if (!a.hit) return;
  EXPECT_TRUE(same(a.si.p, b.si.p) && same(a.si.wi, b.si.wi) && same(a.si.sh_frame.n, b.si.sh_frame.n)) << where;
  EXPECT_EQ(a.si.t, b.si.t) << where;
  EXPECT_EQ(a.si.shape, b.si.shape) << where;
  EXPECT_EQ(a.si.prim, b.si.prim) << where;
}

TEST(TileCameraRaysTest, EntriesAreEachRaysFirstHitTracedOnce) {
  const int W = 16, H = 16;
  auto ts = test::load_test_scene("cbox", W, H);
  ASSERT_TRUE(ts);
  PerspectiveCamera camera(ts->scene->scene().camera, W, H);
  TileCameraRays rays(*ts->scene, camera);
  // A position per pixel, different for each.
  const auto jitter = [](int x, int y) { return Vec2f(0.05f + 0.06f * float(x % 15), 0.93f - 0.05f * float(y % 17)); };
  // A tile on the image's corner: offsets left and up leave the image.
  for (const Tile tile : {Tile{0, 0, 9, 7}, Tile{5, 6, 16, 16}}) {
    for (bool offsets : {false, true}) {
      PathCounters counters;
      rays.begin(tile, W, H, jitter, offsets, counters);
      uint64_t expected_rays = 0;
      for (int y = tile.y0; y < tile.y1; ++y)
        for (int x = tile.x0; x < tile.x1; ++x) {
          const Vec2f j = jitter(x, y);
          PathCounters own;
          const std::string where = std::to_string(x) + "," + std::to_string(y);
          expect_same_hit(rays.base(x, y),
                          trace_camera_hit(*ts->scene, camera.generate_ray({float(x) + j.x, float(y) + j.y}), own),
                          where);
          ++expected_rays;
          if (!offsets) continue;
          for (int o = 0; o < kOffsetCount; ++o) {
            const int nx = x + kOffsetDx[size_t(o)], ny = y + kOffsetDy[size_t(o)];
            if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
            expect_same_hit(rays.offset(x, y, o),
                            trace_camera_hit(*ts->scene, camera.generate_ray({float(nx) + j.x, float(ny) + j.y}), own),
                            where + " offset " + std::to_string(o));
            ++expected_rays;
          }
        }
      EXPECT_EQ(counters.rays, expected_rays) << "every ray traced once, none outside the image";
    }
  }
}

}  // namespace
}  // namespace gdvr
