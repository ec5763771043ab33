// Shift mappings applied forwards and backwards, parametrised over the
// cached-path shifts: shifting the offset back into the base pixel recovers
// the base path (invertibility: docs/gpt.md, "Shift mappings"), and the pair's two MIS
// weights sum to one for every technique (r_forward · r_backward = 1).
#include <gtest/gtest.h>

#include <cmath>

#include "core/gradient/base_path.h"
#include "core/gradient/reconnection_shift.h"
#include "core/gradient/replay_shift.h"
#include "core/render/perspective_camera.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

struct InvertCase {
  ShiftMapping shift;
  const char* scene;
  float diffuse_roughness;  // high values force half-vector copies on veach-mis's rough plates
};

class ShiftInvertibilityTest : public ::testing::TestWithParam<InvertCase> {};

TEST_P(ShiftInvertibilityTest, ShiftingBackRecoversTheBasePathAndWeightsSumToOne) {
  const InvertCase& ic = GetParam();
  const int w = 32, h = ic.scene == std::string("cbox") ? 32 : 18;
  auto ts = test::load_test_scene(ic.scene, w, h);
  ASSERT_TRUE(ts);
  GptSettings gpt = GptSettings::defaults_for(ic.shift);
  gpt.diffuse_roughness = ic.diffuse_roughness;
  PerspectiveCamera camera(ts->desc.camera, w, h);
  PathCounters counters;
  PathRecord base;
  ShiftTrace fwd, bwd;
  int checked = 0, failed = 0, techniques = 0;
  double worst_weight_sum = 0, worst_position = 0, worst_light_point = 0, worst_light_pdf = 0;
  int light_points = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x)
      for (uint32_t s = 0; s < 4; ++s) {
        Sampler sampler(5, 0, uint32_t(x), uint32_t(y), s);
        Vec2f j = sampler.next_2d();
        Ray ray = camera.generate_ray({float(x) + j.x, float(y) + j.y});
        Ray offset_ray = camera.generate_ray({float(x + 1) + j.x, float(y) + j.y});
        trace_base_path(*ts->scene, ts->render.path, ray, sampler, counters, &base);
        if (base.invalid || base.v.empty()) continue;
        bool replay = ic.shift == ShiftMapping::kHybrid;
        ShiftResult r = shift_from_cache(*ts->scene, gpt, base, offset_ray, replay, counters, &fwd);
        if (r.failed) {
          ++failed;
          continue;
        }
        ShiftResult back = shift_from_cache(*ts->scene, gpt, fwd.offset, ray, replay, counters, &bwd);
        ++checked;
        EXPECT_FALSE(back.failed) << "forward succeeded, backward failed at " << x << "," << y << " s=" << s;
        if (back.failed) continue;
        ASSERT_EQ(fwd.ratios.size(), bwd.ratios.size());
        for (size_t t = 0; t < fwd.ratios.size(); ++t) {
          if (fwd.ratios[t] == 0.0) continue;  // the offset lacks this technique: w = 1 on both sides
          double w_sum = pair_mis_weight(fwd.ratios[t], 0) + pair_mis_weight(bwd.ratios[t], 0);
          worst_weight_sum = std::max(worst_weight_sum, std::abs(w_sum - 1.0));
          ++techniques;
        }
        ASSERT_EQ(bwd.offset.v.size(), std::min(base.v.size(), bwd.offset.v.size()));
        for (size_t k = 0; k < bwd.offset.v.size(); ++k) {
          Vec3f d = bwd.offset.v[k].si.p - base.v[k].si.p;
          float scale = 1.0f + max_component(Vec3f(std::abs(base.v[k].si.p.x), std::abs(base.v[k].si.p.y),
                                                   std::abs(base.v[k].si.p.z)));
          worst_position = std::max(worst_position, double(length(d) / scale));
          // The emitter sample: the reverse shift, replaying the light
          // sample's random numbers from the recovered vertex, lands on the
          // base's light point (or direction, for an infinitely distant one).
          const EmitterSample& eb = base.v[k].es;
          if (base.v[k].has_nee && eb.pdf > 0) {
            const EmitterSample& ebk = bwd.offset.v[k].es;
            EXPECT_EQ(ebk.emitter, eb.emitter);
            const Vec3f pb = base.v[k].si.p + eb.d * eb.dist, pk = bwd.offset.v[k].si.p + ebk.d * ebk.dist;
            const double error = std::isfinite(eb.dist) ? double(length(pk - pb) / (1.0f + length(pb)))
                                                        : double(length(ebk.d - eb.d));
            worst_light_point = std::max(worst_light_point, error);
            if (ebk.pdf > 0)
              worst_light_pdf = std::max(worst_light_pdf, std::abs(double(ebk.pdf) / double(eb.pdf) - 1.0));
            ++light_points;
          }
        }
      }
  std::printf("[ invertibility ] %s %s thr %.3g: %d pairs checked, %d forward failures, %d techniques, worst |w+w'-1| "
              "%.2e, worst relative position error %.2e, %d light points: worst error %.2e, worst pdf error %.2e\n",
              shift_mapping_name(ic.shift), ic.scene, ic.diffuse_roughness, checked, failed, techniques,
              worst_weight_sum, worst_position, light_points, worst_light_point, worst_light_pdf);
  EXPECT_GT(checked, 100);
  // Float geometry (cosines near grazing, spawn offsets) limits the agreement;
  // a wrong Jacobian or pdf shows as an O(1) error.
  EXPECT_LT(worst_weight_sum, 1e-2);
  EXPECT_LT(worst_position, 1e-4);
  EXPECT_GT(light_points, 100);
  EXPECT_LT(worst_light_point, 1e-4);
  EXPECT_LT(worst_light_pdf, 1e-3);
}

TEST(ShiftReplayTest, ReplayWeightsAreOneHalfAndTheOffsetIsThePathTracer) {
  auto ts = test::load_test_scene("cbox", 16, 16);
  ASSERT_TRUE(ts);
  PerspectiveCamera camera(ts->desc.camera, 16, 16);
  PathCounters counters;
  PathRecord base, offset;
  Sampler sampler(3, 0, 4, 5, 0);
  Vec2f j = sampler.next_2d();
  Sampler after = sampler;
  trace_base_path(*ts->scene, ts->render.path, camera.generate_ray({4 + j.x, 5 + j.y}), sampler, counters, &base);
  Ray offset_ray = camera.generate_ray({5 + j.x, 5 + j.y});
  ShiftResult r = replay_shift(*ts->scene, ts->render.path, base, offset_ray, after, counters);
  Sampler again = after;
  trace_base_path(*ts->scene, ts->render.path, offset_ray, again, counters, &offset);
  EXPECT_FALSE(r.failed);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(r.gradient[c], 0.5f * (offset.indirect[c] - base.indirect[c]), 1e-5f);
    EXPECT_NEAR(r.offset_primal[c], 0.5f * offset.indirect[c], 1e-5f);
  }
}

INSTANTIATE_TEST_SUITE_P(Shift, ShiftInvertibilityTest,
                         ::testing::Values(InvertCase{ShiftMapping::kReconnect, "cbox", 0.001f},
                                           InvertCase{ShiftMapping::kReconnect, "veach-mis", 0.001f},
                                           InvertCase{ShiftMapping::kReconnect, "veach-mis", 10.0f},
                                           InvertCase{ShiftMapping::kReconnect, "matpreview", 0.001f},
                                           InvertCase{ShiftMapping::kHybrid, "cbox", 0.001f},
                                           InvertCase{ShiftMapping::kHybrid, "veach-mis", 10.0f},
                                           InvertCase{ShiftMapping::kHybrid, "matpreview", 0.001f}),
                         [](const auto& info) {
                           std::string s = std::string(shift_mapping_name(info.param.shift)) + "_" + info.param.scene +
                                           (info.param.diffuse_roughness > 1 ? "_glossy" : "");
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

}  // namespace
}  // namespace gdvr
