// MIS weights of the cached-path shifts on every stiff scene, through G-PT's
// test hook (ShiftTrace: the ratio of every technique): each ratio is a
// number >= 0 (or +Inf, weight 0), each pair weight lies in [0, 1], and the
// gradient sample is finite. Random replay has no hook: its weights are 1/2
// by construction (ShiftReplayTest checks that on cbox).
#include <gtest/gtest.h>

#include <ostream>

#include "core/gradient/base_path.h"
#include "core/gradient/reconnection_shift.h"
#include "core/render/perspective_camera.h"
#include "tests/core/stiff/stiff_test_util.h"

namespace gdvr::stiff {
namespace {

struct MisParam {
  StiffCase c;
  ShiftMapping shift;
};
// Readable names in ctest output instead of the parameter's bytes.
void PrintTo(const MisParam& p, std::ostream* os) { *os << p.c.name << "/" << shift_mapping_name(p.shift); }

class StiffMisTest : public ::testing::TestWithParam<MisParam> {};

TEST_P(StiffMisTest, WeightsInUnitIntervalAndGradientsFinite) {
  const StiffCase& c = GetParam().c;
  auto desc = load_case(c);
  ASSERT_TRUE(desc.ok()) << desc.status().to_string();
  auto scene = FrameScene::create(*desc, {});
  ASSERT_TRUE(scene.ok()) << scene.status().to_string();
  const GptSettings gpt = GptSettings::defaults_for(GetParam().shift);
  const bool replay_prefix = GetParam().shift == ShiftMapping::kHybrid;
  PathTracerSettings path;
  path.max_depth = desc->defaults.max_depth;
  path.rr_depth = desc->defaults.rr_depth;
  const int w = c.res, h = c.res;
  PerspectiveCamera camera(desc->camera, w, h);
  PathCounters counters;
  PathRecord base;
  ShiftTrace trace;
  int64_t techniques = 0, inf_ratios = 0, shifts = 0, failures = 0;
  double max_ratio = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (uint32_t s = 0; s < 4; ++s)
        for (int dir = 0; dir < 2; ++dir) {
          const int nx = x + (dir == 0), ny = y + (dir == 1);
          if (nx >= w || ny >= h) continue;
          Sampler sampler(7, 0, uint32_t(x), uint32_t(y), s);
          const Vec2f j = sampler.next_2d();
          const Ray ray = camera.generate_ray({float(x) + j.x, float(y) + j.y});
          const Ray offset_ray = camera.generate_ray({float(nx) + j.x, float(ny) + j.y});
          trace_base_path(*scene.value(), path, ray, sampler, counters, &base);
          if (base.invalid) continue;
          ShiftResult r = shift_from_cache(*scene.value(), gpt, base, offset_ray, replay_prefix, counters, &trace);
          ++shifts;
          failures += r.failed;
          ASSERT_TRUE(is_finite(r.gradient)) << "pixel " << x << "," << y << " s=" << s;
          ASSERT_TRUE(is_finite(r.offset_primal)) << "pixel " << x << "," << y << " s=" << s;
          for (double ratio : trace.ratios) {
            ASSERT_FALSE(std::isnan(ratio)) << "pixel " << x << "," << y << " s=" << s;
            ASSERT_GE(ratio, 0.0) << "pixel " << x << "," << y << " s=" << s;
            const double wgt = pair_mis_weight(ratio, gpt.mis_epsilon);
            ASSERT_GE(wgt, 0.0);
            ASSERT_LE(wgt, 1.0);
            ++techniques;
            if (std::isinf(ratio)) ++inf_ratios;
            else max_ratio = std::max(max_ratio, ratio);
          }
        }
  std::printf("[ mis ] %-18s %-9s %lld shifts, %lld failed, %lld techniques, %lld infinite ratios, max ratio %.3g, "
              "%llu non-finite samples dropped\n",
              c.name, shift_mapping_name(GetParam().shift), (long long)shifts, (long long)failures,
              (long long)techniques, (long long)inf_ratios, max_ratio, (unsigned long long)counters.invalid_samples);
  EXPECT_GT(shifts, 0);
  if (!c.black) {
    EXPECT_GT(techniques, 0);
  }
}

std::vector<MisParam> mis_params() {
  std::vector<MisParam> v;
  for (const StiffCase& c : stiff_cases())
    for (ShiftMapping m : {ShiftMapping::kReconnect, ShiftMapping::kHybrid}) v.push_back({c, m});
  return v;
}

INSTANTIATE_TEST_SUITE_P(Stiff, StiffMisTest, ::testing::ValuesIn(mis_params()), [](const auto& info) {
  return std::string(info.param.c.name) + "_" + shift_mapping_name(info.param.shift);
});

}  // namespace
}  // namespace gdvr::stiff
