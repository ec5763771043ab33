#include <gtest/gtest.h>

#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

// A few grossly wrong gradients (a "firefly" in the gradient buffers) smear
// into a halo under L2 but are voted down under L1 (docs/reconstruction.md).
TEST(IrlsL1Test, RobustToPlantedOutlierGradientsWhereL2IsNot) {
  for (int frames : {1, 3}) {
    test::SceneOptions o;
    o.frames = frames;
    o.temporal = frames > 1;
    o.primal_sigma = 0.01f;
    GradientWindow w = test::make_window(o);
    const int spots[][2] = {{5, 5}, {30, 8}, {12, 25}, {25, 20}};
    for (auto& s : spots)
      for (int c = 0; c < 3; ++c) {
        test::mutable_frame(w, 0).buffer(Term::kDx).at(s[0], s[1], c) += 4.0f;
        test::mutable_frame(w, 0).buffer(Term::kDy).at(s[0] + 1, s[1] + 2, c) -= 3.0f;
      }
    ReconSettings l2, l1;
    l1.method = ReconMethod::kL1;
    auto r2 = reconstruct(w, l2);
    auto r1 = reconstruct(w, l1);
    ASSERT_TRUE(r1.ok() && r2.ok());
    const auto e2 = test::frame_error(r2->frames[0], 0);
    const auto e1 = test::frame_error(r1->frames[0], 0);
    EXPECT_GT(e2.max, 0.5) << "L2 should visibly suffer";
    EXPECT_LT(e1.max, 0.2 * e2.max);
    EXPECT_LT(e1.rms, 0.25 * e2.rms);
  }
}

TEST(IrlsL1Test, ConvergesTowardsL2OnCleanData) {
  test::SceneOptions o;
  o.primal_sigma = 0.05f;
  o.gradient_sigma = 0.005f;
  GradientWindow w = test::make_window(o);
  ReconSettings l1;
  l1.method = ReconMethod::kL1;
  auto r1 = reconstruct(w, l1);
  ASSERT_TRUE(r1.ok());
  EXPECT_LT(test::frame_error(r1->frames[0], 0).rms, 0.02);
  EXPECT_GT(r1->stats.cg_iterations, 0);
  EXPECT_EQ(r1->stats.outer_iterations, l1.l1_outer_iterations);
}

}  // namespace
}  // namespace gdvr
