// The reconnection shift skips the visibility ray of a reconnection into a
// vertex after which nothing can contribute (PathVertex::dark_suffix). The
// skip must change nothing but the ray count: the same gradient and offset
// primal, bit for bit, as the traced run (which never skips, see
// reconnection_shift.cpp), and no failure the traced run does not have.
#include <gtest/gtest.h>

#include "core/gradient/base_path.h"
#include "core/gradient/reconnection_shift.h"
#include "core/render/perspective_camera.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

struct DarkCase {
  ShiftMapping shift;
  const char* scene;
};

class DarkSuffixTest : public ::testing::TestWithParam<DarkCase> {};

TEST_P(DarkSuffixTest, SkippedReconnectionsChangeNothingButTheRayCount) {
  const DarkCase& dc = GetParam();
  const int w = 32, h = dc.scene == std::string("cbox") ? 32 : 18;
  auto ts = test::load_test_scene(dc.scene, w, h);
  ASSERT_TRUE(ts);
  const GptSettings gpt = GptSettings::defaults_for(dc.shift);
  const bool replay_prefix = dc.shift == ShiftMapping::kHybrid;
  PerspectiveCamera camera(ts->desc.camera, w, h);
  PathCounters base_counters;
  PathRecord base;
  ShiftTrace trace;
  int shifts = 0, dark_vertices = 0, vertices = 0, failures_skipped = 0;
  uint64_t rays_traced = 0, rays_skipping = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x)
      for (uint32_t s = 0; s < 4; ++s) {
        Sampler sampler(11, 0, uint32_t(x), uint32_t(y), s);
        const Vec2f j = sampler.next_2d();
        trace_base_path(*ts->scene, ts->render.path, camera.generate_ray({float(x) + j.x, float(y) + j.y}), sampler,
                        base_counters, &base);
        if (base.invalid || base.v.empty()) continue;
        // dark_suffix promises that no base technique from x_k on contributes
        // (x_k's own emission aside).
        for (size_t k = 0; k < base.v.size(); ++k) {
          ++vertices;
          if (!base.v[k].dark_suffix) continue;
          ++dark_vertices;
          for (size_t i = k; i < base.v.size(); ++i) {
            EXPECT_TRUE(base.v[i].nee.is_black()) << "vertex " << i << " of a suffix dark from " << k;
            EXPECT_TRUE(base.v[i].escape.is_black()) << "vertex " << i << " of a suffix dark from " << k;
            if (i > k) {
              EXPECT_TRUE(base.v[i].emission.is_black()) << "vertex " << i << " of a suffix dark from " << k;
            }
          }
        }
        const Ray offset_ray = camera.generate_ray({float(x + 1) + j.x, float(y) + j.y});
        PathCounters with_trace, skipping;
        const ShiftResult full = shift_from_cache(*ts->scene, gpt, base, offset_ray, replay_prefix, with_trace, &trace);
        const ShiftResult fast = shift_from_cache(*ts->scene, gpt, base, offset_ray, replay_prefix, skipping);
        ++shifts;
        rays_traced += with_trace.rays;
        rays_skipping += skipping.rays;
        for (int c = 0; c < 3; ++c) {
          EXPECT_EQ(fast.gradient[c], full.gradient[c]) << "pixel " << x << "," << y << " s=" << s;
          EXPECT_EQ(fast.offset_primal[c], full.offset_primal[c]) << "pixel " << x << "," << y << " s=" << s;
        }
        EXPECT_LE(skipping.rays, with_trace.rays);
        EXPECT_TRUE(!fast.failed || full.failed) << "the skip added a failure";
        if (full.failed && !fast.failed) ++failures_skipped;
      }
  std::printf("[ dark suffix ] %s %s: %d shifts, %d of %d vertices dark, rays %llu traced vs %llu "
              "skipping, %d failures not tested\n",
              shift_mapping_name(dc.shift), dc.scene, shifts, dark_vertices, vertices,
              (unsigned long long)rays_traced, (unsigned long long)rays_skipping, failures_skipped);
  EXPECT_GT(shifts, 500);
  // The scenes have dark suffixes (paths escaping into the black background
  // or whose later light samples are occluded): the skip must take effect.
  EXPECT_GT(dark_vertices, 0);
  EXPECT_LT(rays_skipping, rays_traced);
}

INSTANTIATE_TEST_SUITE_P(CachedShifts, DarkSuffixTest,
                         ::testing::Values(DarkCase{ShiftMapping::kReconnect, "cbox"},
                                           DarkCase{ShiftMapping::kReconnect, "veach-mis"},
                                           DarkCase{ShiftMapping::kHybrid, "veach-mis"}),
                         [](const auto& info) {
                           std::string name = std::string(shift_mapping_name(info.param.shift)) + "_" +
                                              info.param.scene;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

}  // namespace
}  // namespace gdvr
