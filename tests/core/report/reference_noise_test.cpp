#include "core/report/reference_noise.h"

#include <gtest/gtest.h>

#include <random>

#include "core/image/error_metrics.h"

namespace gdvr {
namespace {

Image filled(int w, int h, float v) {
  Image im(w, h, 3);
  for (float& x : im.data()) x = v;
  return im;
}

TEST(ReferenceNoiseTest, FloorsFollowTheFormsOfEachFigure) {
  // Two frames of a flat 0.5 image with variance 0.01 and 0.03.
  const Image r0 = filled(4, 2, 0.5f), r1 = filled(4, 2, 0.5f);
  const Image v0 = filled(4, 2, 0.01f), v1 = filled(4, 2, 0.03f);
  auto f = reference_noise_floor({&r0, &r1}, {&v0, &v1});
  ASSERT_TRUE(f.ok()) << f.status().to_string();
  EXPECT_NEAR(f->global, 0.02 / 0.25, 1e-7);  // mean variance / mean R² (float images)
  EXPECT_NEAR(f->per_pixel, 0.02 / (0.25 + 0.01), 1e-7);
  EXPECT_NEAR(f->flicker, 0.01 + 0.03, 1e-7);  // Var(R_t) + Var(R_t+1)
}

TEST(ReferenceNoiseTest, PredictsTheErrorOfANoisyCopyOfTheTruth) {
  // A "reference" that is the truth plus Gaussian noise of known variance: its
  // measured figures against the truth match the floor computed from the
  // variance alone (the quantity the floor claims to be).
  std::mt19937 rng(7);
  const int w = 64, h = 64, frames = 6;
  std::vector<Image> truth, noisy, var;
  std::uniform_real_distribution<float> level(0.05f, 2.0f);
  for (int t = 0; t < frames; ++t) {
    Image tr(w, h, 3), nz(w, h, 3), vr(w, h, 3);
    for (size_t i = 0; i < tr.data().size(); ++i) {
      const float v = level(rng), sigma = 0.05f * v;
      tr.data()[i] = v;
      nz.data()[i] = v + std::normal_distribution<float>(0.0f, sigma)(rng);
      vr.data()[i] = sigma * sigma;
    }
    truth.push_back(std::move(tr));
    noisy.push_back(std::move(nz));
    var.push_back(std::move(vr));
  }
  std::vector<const Image*> t_ptr, n_ptr, v_ptr;
  for (int t = 0; t < frames; ++t) {
    t_ptr.push_back(&truth[size_t(t)]);
    n_ptr.push_back(&noisy[size_t(t)]);
    v_ptr.push_back(&var[size_t(t)]);
  }
  auto floor = reference_noise_floor(t_ptr, v_ptr);
  ASSERT_TRUE(floor.ok());
  RelMseSums sums;
  for (int t = 0; t < frames; ++t) sums.add(rel_mse_sums(noisy[size_t(t)], truth[size_t(t)]).value());
  auto flicker = temporal_flicker(n_ptr, t_ptr);
  ASSERT_TRUE(flicker.ok());
  EXPECT_NEAR(sums.global() / floor->global, 1.0, 0.03);
  EXPECT_NEAR(sums.per_pixel() / floor->per_pixel, 1.0, 0.03);
  EXPECT_NEAR(flicker.value() / floor->flicker, 1.0, 0.03);
}

TEST(ReferenceNoiseTest, RejectsMismatchedInputs) {
  const Image r = filled(4, 4, 1.0f), v_small = filled(2, 2, 0.1f);
  auto a = reference_noise_floor({&r}, {&v_small});
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.status().message().find("variance of frame 0"), std::string::npos) << a.status().message();
  auto b = reference_noise_floor({&r, &r}, {&r});
  EXPECT_FALSE(b.ok());
  auto c = reference_noise_floor({}, {});
  EXPECT_FALSE(c.ok());
  // One frame: no flicker floor, the other two are known.
  auto d = reference_noise_floor({&r}, {&r});
  ASSERT_TRUE(d.ok());
  EXPECT_TRUE(std::isnan(d->flicker));
  EXPECT_NEAR(d->global, 1.0, 1e-9);
}

}  // namespace
}  // namespace gdvr
