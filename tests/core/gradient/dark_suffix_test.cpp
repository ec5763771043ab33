// How the reconnection shift uses the base path's light-sample visibility:
// - it skips the visibility ray of a reconnection into a vertex after which
//   nothing can contribute (PathVertex::dark_suffix). The skip must change
//   nothing but the ray count: the same gradient and offset primal, bit for
//   bit, as the traced run (which never skips, see reconnection_shift.cpp),
//   and no failure the traced run does not have;
// - at the vertex it reconnects into, it reuses the base's shadow ray, and
//   tests that ray itself where the base did not (its BSDF value was zero).
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

// An offset reconnecting into x_k evaluates the BSDF there for its own
// incoming direction; where the base's value was zero the base traced no
// shadow ray. Simulated on real paths: the record of a vertex with a visible
// light sample is rewritten as if the base's BSDF value had been zero. For an
// offset that reconnects exactly into that vertex nothing it computes
// depends on the base's value, so its weighted contributions must not change.
TEST(ReconnectionShadowTest, AnUntestedBaseShadowRayIsTestedByTheOffset) {
  const int w = 32, h = 32;
  auto ts = test::load_test_scene("cbox", w, h);
  ASSERT_TRUE(ts);
  const GptSettings gpt = GptSettings::defaults_for(ShiftMapping::kReconnect);
  PerspectiveCamera camera(ts->desc.camera, w, h);
  PathCounters counters;
  PathRecord base;
  ShiftTrace trace;
  int checked = 0, dark_after = 0;
  uint64_t extra_rays = 0;
  const auto same_point = [](Vec3f a, Vec3f b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      Sampler sampler(21, 0, uint32_t(x), uint32_t(y), 0);
      const Vec2f j = sampler.next_2d();
      trace_base_path(*ts->scene, ts->render.path, camera.generate_ray({float(x) + j.x, float(y) + j.y}), sampler,
                      counters, &base);
      if (base.invalid || base.v.size() < 2) continue;
      const Ray offset_ray = camera.generate_ray({float(x + 1) + j.x, float(y) + j.y});
      PathCounters original_rays;
      const ShiftResult original = shift_from_cache(*ts->scene, gpt, base, offset_ray, false, original_rays, &trace);
      if (original.failed) continue;
      // The vertex the offset reconnected into: the first it shares with the base.
      size_t k = 0;
      while (k < trace.offset.v.size() && !same_point(trace.offset.v[k].si.p, base.v[k].si.p)) ++k;
      if (k == 0 || k >= trace.offset.v.size() || !base.v[k].nee_visible || base.v[k].nee.is_black()) continue;
      PathRecord untested = base;
      untested.v[k].nee_f = Rgb(0.0f);
      untested.v[k].nee = Rgb(0.0f);
      untested.v[k].nee_visible = false;
      ASSERT_TRUE(untested.v[k].shadow_untested());
      mark_dark_suffixes(&untested);
      PathCounters untested_rays, skipping_rays;
      const ShiftResult r = shift_from_cache(*ts->scene, gpt, untested, offset_ray, false, untested_rays, &trace);
      // Without the trace the dark-suffix skip is active: it must not skip
      // this reconnection, whose light sample only the offset can test.
      const ShiftResult fast = shift_from_cache(*ts->scene, gpt, untested, offset_ray, false, skipping_rays);
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(r.offset_primal[c], original.offset_primal[c]) << x << "," << y;
        EXPECT_EQ(fast.offset_primal[c], original.offset_primal[c]) << x << "," << y;
      }
      EXPECT_EQ(untested_rays.rays, original_rays.rays + 1) << "the offset traces the skipped shadow ray";
      extra_rays += untested_rays.rays - original_rays.rays;
      if (untested.v[k].dark_suffix) ++dark_after;
      ++checked;
    }
  std::printf("[ untested shadow ] cbox: %d reconnections into a lit vertex (%d with nothing lit after it), %llu "
              "shadow rays traced by offsets\n",
              checked, dark_after, (unsigned long long)extra_rays);
  EXPECT_GT(checked, 50);
  EXPECT_GT(dark_after, 10);  // the skip's own check of the untested light sample is exercised
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
