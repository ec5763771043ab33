// Every solver must return the exact image when fed exact gradients
// (a known answer: exact gradients must reconstruct the exact image),
// for a single frame and for a 5-frame window with temporal terms.
#include <gtest/gtest.h>

#include <tuple>

#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

using test::SceneOptions;


class ReconExactTest : public ::testing::TestWithParam<std::tuple<ReconMethod, int>> {
 protected:
  ReconSettings settings() const {
    ReconSettings s;
    s.method = std::get<0>(GetParam());
    s.l2_tolerance = 1e-6;
    s.l2_max_iterations = 1000;
    s.cv_iterations = 300;
    return s;
  }
  SceneOptions scene() const {
    SceneOptions o;
    o.frames = std::get<1>(GetParam());
    o.temporal = o.frames > 1;
    o.variances = true;
    return o;
  }
};

TEST_P(ReconExactTest, ExactPrimalAndGradientsGiveExactImage) {
  SceneOptions o = scene();
  // Exact buffers have zero variance: give the weighted method a tiny one.
  GradientWindow w = test::make_window(o);
  auto r = reconstruct(w, settings());
  ASSERT_TRUE(r.ok()) << r.status().to_string();
  ASSERT_EQ(int(r->frames.size()), o.frames);
  for (int t = 0; t < o.frames; ++t) EXPECT_LT(test::frame_error(r->frames[t], t).max, 2e-3) << "frame " << t;
}

TEST_P(ReconExactTest, NoisyPrimalExactGradientsRecoversImage) {
  SceneOptions o = scene();
  o.primal_sigma = 0.1f;
  GradientWindow w = test::make_window(o);
  test::mark_gradients_exact(w);
  auto r = reconstruct(w, settings());
  ASSERT_TRUE(r.ok()) << r.status().to_string();
  // A screened Poisson solve with exact gradients keeps only the low
  // frequencies of the primal noise, α²/(α² + |D|²): the error is a small
  // fraction of σ. Uniform control variates act like α = 1 and keep more.
  const double limit = std::get<0>(GetParam()) == ReconMethod::kUniform ? 0.5 : 0.2;
  for (int t = 0; t < o.frames; ++t) EXPECT_LT(test::frame_error(r->frames[t], t).rms, limit * 0.1) << "frame " << t;
}

INSTANTIATE_TEST_SUITE_P(Recon, ReconExactTest,
                         ::testing::Combine(::testing::Values(ReconMethod::kL2, ReconMethod::kL1,
                                                              ReconMethod::kUniform, ReconMethod::kWeighted),
                                            ::testing::Values(1, 5)),
                         [](const auto& info) {
                           return std::string(recon_method_name(std::get<0>(info.param))) + "_W" +
                                  std::to_string(std::get<1>(info.param));
                         });

}  // namespace
}  // namespace gdvr
