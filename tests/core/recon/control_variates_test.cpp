#include <gtest/gtest.h>

#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

TEST(ControlVariateTest, WeightedNeedsVariances) {
  GradientWindow w = test::make_window(test::SceneOptions());
  ReconSettings s;
  s.method = ReconMethod::kWeighted;
  auto r = reconstruct(w, s);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("variance"), std::string::npos);
}

// Rousselle et al. 2016: inverse-variance weights make the reconstruction
// robust to a region of very noisy gradients that the uniform one trusts.
TEST(ControlVariateTest, WeightedBeatsUniformWhenSomeGradientsAreNoisy) {
  test::SceneOptions o;
  o.primal_sigma = 0.05f;
  o.gradient_sigma = 0.005f;
  o.variances = true;
  GradientWindow w = test::make_window(o);
  GradientFrame& f = test::mutable_frame(w, 0);
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss(0.0f, 0.5f);
  for (int y = 8; y < 24; ++y)
    for (int x = 8; x < 24; ++x)
      for (int c = 0; c < 3; ++c) {
        f.buffer(Term::kDx).at(x, y, c) += gauss(rng);
        f.variance(Term::kDx).at(x, y, c) = 0.25f;
      }
  ReconSettings uni, wei;
  uni.method = ReconMethod::kUniform;
  wei.method = ReconMethod::kWeighted;
  auto ru = reconstruct(w, uni);
  auto rw = reconstruct(w, wei);
  ASSERT_TRUE(ru.ok() && rw.ok());
  EXPECT_LT(test::frame_error(rw->frames[0], 0).rms, 0.5 * test::frame_error(ru->frames[0], 0).rms);
}

}  // namespace
}  // namespace gdvr
