// The trust map of a denoised data term (core/recon/data_term_weight.h) on
// images with known answers, and the solvers' use of it.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/recon/data_term_weight.h"
#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

struct Passes {
  Image dx_a, dx_b, dy_a, dy_b;
};

// Two passes' forward differences of `truth`, each with independent Gaussian noise.
Passes noisy_gradients(const Image& truth, float sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.0f, sigma);
  const int w = truth.width(), h = truth.height(), C = truth.channels();
  Passes p{Image(w, h, C), Image(w, h, C), Image(w, h, C), Image(w, h, C)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < C; ++c) {
        const float gx = x + 1 < w ? truth.at(x + 1, y, c) - truth.at(x, y, c) : 0.0f;
        const float gy = y + 1 < h ? truth.at(x, y + 1, c) - truth.at(x, y, c) : 0.0f;
        p.dx_a.at(x, y, c) = gx + gauss(rng);
        p.dx_b.at(x, y, c) = gx + gauss(rng);
        p.dy_a.at(x, y, c) = gy + gauss(rng);
        p.dy_b.at(x, y, c) = gy + gauss(rng);
      }
  return p;
}

// A vertical step from 0.2 to 1.2 at x = 24, and the same blurred by a
// 7-pixel box along x: a denoiser's soft edge.
Image step(int w, int h, int blur) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float sum = 0;
      for (int k = -blur; k <= blur; ++k) sum += (x + k >= 24) ? 1.2f : 0.2f;
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = sum / float(2 * blur + 1);
    }
  return img;
}

double mean_over(const Image& m, int x0, int x1) {
  double s = 0;
  int n = 0;
  for (int y = 0; y < m.height(); ++y)
    for (int x = x0; x < x1; ++x) s += m.at(x, y, 0), ++n;
  return s / n;
}

TEST(DataTermWeightTest, TrustsAgreementAndNotABlurredEdge) {
  const int w = 64, h = 32;
  const Image truth = step(w, h, 0), blurred = step(w, h, 3);
  const Passes g = noisy_gradients(truth, 0.05f, 7);
  DataTermWeightSettings s;  // radius 4, cap 20
  auto right = data_term_weight(truth, g.dx_a, g.dx_b, g.dy_a, g.dy_b, s);
  auto soft = data_term_weight(blurred, g.dx_a, g.dx_b, g.dy_a, g.dy_b, s);
  ASSERT_TRUE(right.ok() && soft.ok()) << right.status().to_string() << soft.status().to_string();
  for (float v : soft->data()) ASSERT_TRUE(v >= 1.0f && v <= 20.0f);
  // The exact data term agrees with the gradients everywhere: its bias
  // estimate is noise around 0, so the multiplier is high on average.
  EXPECT_GT(mean_over(right.value(), 0, w), 8.0);
  // The blurred edge is off by far more than the gradients' noise: the
  // gradients decide there (multiplier 1)...
  EXPECT_LT(mean_over(soft.value(), 22, 27), 1.05);
  // ...and away from it (beyond blur + radius) the blurred image is exact.
  EXPECT_GT(mean_over(soft.value(), 0, 12), 8.0);
  EXPECT_GT(mean_over(soft.value(), 36, w), 8.0);
}

// Noisier gradients make the same bias matter less: the multiplier grows
// with the gradients' noise (m = sqrt(variance / bias²)).
TEST(DataTermWeightTest, NoisierGradientsTrustTheDataTermMore) {
  const int w = 64, h = 32;
  const Image truth = step(w, h, 0), blurred = step(w, h, 3);
  double near_edge[2];
  const float sigmas[2] = {0.05f, 1.0f};
  for (int k = 0; k < 2; ++k) {
    const Passes g = noisy_gradients(truth, sigmas[k], 11);
    auto m = data_term_weight(blurred, g.dx_a, g.dx_b, g.dy_a, g.dy_b);
    ASSERT_TRUE(m.ok());
    near_edge[k] = mean_over(m.value(), 20, 29);
  }
  EXPECT_GT(near_edge[1], 2.0 * near_edge[0]) << near_edge[0] << " " << near_edge[1];
}

TEST(DataTermWeightTest, UnusableGradientsLeaveTheDataTermTrusted) {
  const int w = 16, h = 12;
  const Image d = step(w, h, 0);
  Image nan(w, h, 3);
  for (float& v : nan.data()) v = std::nanf("");
  auto m = data_term_weight(d, nan, nan, nan, nan);
  ASSERT_TRUE(m.ok());
  for (float v : m->data()) EXPECT_EQ(v, 20.0f);
}

TEST(DataTermWeightTest, RefusesMismatchedShapesAndBadSettings) {
  const Image d(8, 8, 3), other(8, 7, 3);
  EXPECT_EQ(data_term_weight(d, d, d, d, other).status().code(), StatusCode::kInvalidArgument);
  DataTermWeightSettings s;
  s.max_multiplier = 0.5;
  EXPECT_EQ(data_term_weight(d, d, d, d, d, s).status().code(), StatusCode::kInvalidArgument);
}

// A constant multiplier c on every pixel is the same problem as α·c, for
// both solvers (L2 then runs its float-weight operator, L1 scales its
// primal weights). L1's low-frequency correction keeps the base α (it gives
// back the data term's low frequencies at the scale the gradients cannot
// reach), so it is off here, and L1 runs its full schedule on both.
TEST(DataTermWeightTest, AConstantMultiplierIsAScaledAlpha) {
  for (ReconMethod method : {ReconMethod::kL2, ReconMethod::kL1}) {
    test::SceneOptions o;
    o.frames = 3;
    o.temporal = true;
    o.primal_sigma = 0.05f;
    o.gradient_sigma = 0.01f;
    GradientWindow weighted = test::make_window(o);
    for (int t = 0; t < 3; ++t) {
      Image& m = test::mutable_frame(weighted, t).data_weight;
      m = Image(o.width, o.height, 1);
      for (float& v : m.data()) v = 2.5f;
    }
    ReconSettings with_map, scaled;
    with_map.method = scaled.method = method;
    with_map.l2_tolerance = scaled.l2_tolerance = 1e-6;
    with_map.l1_inner_tolerance = scaled.l1_inner_tolerance = 1e-6;
    with_map.l1_low_frequencies_from_primal = scaled.l1_low_frequencies_from_primal = false;
    // A map also selects L1's denoised-term schedule (irls_l1.cpp): the same rounds here.
    with_map.l1_denoised_outer_iterations = with_map.l1_outer_iterations;
    with_map.l1_denoised_epsilon0 = with_map.l1_epsilon0;
    with_map.l1_denoised_epsilon_decay = with_map.l1_epsilon_decay;
    scaled.alpha = with_map.alpha * 2.5;
    auto a = reconstruct(weighted, with_map);
    auto b = reconstruct(test::make_window(o), scaled);
    ASSERT_TRUE(a.ok() && b.ok());
    double max_diff = 0;
    for (int t = 0; t < 3; ++t)
      for (size_t i = 0; i < a->frames[t].data().size(); ++i)
        max_diff = std::max(max_diff, double(std::fabs(a->frames[t].data()[i] - b->frames[t].data()[i])));
    EXPECT_LT(max_diff, 2e-3) << recon_method_name(method);
    // and not the unscaled problem
    auto c = reconstruct(test::make_window(o), with_map);
    ASSERT_TRUE(c.ok());
    double max_unscaled = 0;
    for (size_t i = 0; i < a->frames[1].data().size(); ++i)
      max_unscaled = std::max(max_unscaled, double(std::fabs(a->frames[1].data()[i] - c->frames[1].data()[i])));
    EXPECT_GT(max_unscaled, 10 * max_diff) << recon_method_name(method);
  }
}

TEST(DataTermWeightTest, AMisshapenMapIsRefused) {
  test::SceneOptions o;
  GradientWindow w = test::make_window(o);
  test::mutable_frame(w, 0).data_weight = Image(o.width, o.height, 3);
  auto r = reconstruct(w, ReconSettings());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("data weight"), std::string::npos) << r.status().message();
}

}  // namespace
}  // namespace gdvr
