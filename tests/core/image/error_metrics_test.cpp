// relMSE (both forms), flicker and log-log interpolation on known arrays.
#include "core/image/error_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gdvr {
namespace {

Image filled(int w, int h, float v) {
  Image im(w, h, 3);
  std::fill(im.data().begin(), im.data().end(), v);
  return im;
}

TEST(ReportErrorMetricsTest, RelMseBothFormsOnKnownValues) {
  // reference 1 everywhere, image 2: global = Σ1 / Σ1 = 1; per-pixel = 1 / (1 + 0.01).
  auto s = rel_mse_sums(filled(3, 2, 2.0f), filled(3, 2, 1.0f));
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  EXPECT_DOUBLE_EQ(s->global(), 1.0);
  EXPECT_NEAR(s->per_pixel(), 1.0 / 1.01, 1e-12);
  EXPECT_EQ(s->count, 18);

  // Mixed pixels: reference (0, 1) with image (0.1, 1.5) in every channel.
  Image ref(2, 1, 3), img(2, 1, 3);
  for (int c = 0; c < 3; ++c) {
    ref.at(0, 0, c) = 0.0f, img.at(0, 0, c) = 0.1f;
    ref.at(1, 0, c) = 1.0f, img.at(1, 0, c) = 1.5f;
  }
  auto m = rel_mse_sums(img, ref);
  ASSERT_TRUE(m.ok());
  const double d0 = double(0.1f) * 0.1f, d1 = 0.25;
  EXPECT_NEAR(m->global(), (3 * d0 + 3 * d1) / 3.0, 1e-9);
  EXPECT_NEAR(m->per_pixel(), (d0 / 0.01 + d1 / 1.01) / 2.0, 1e-6);
  // A black reference: the global form is 0, not NaN.
  auto black = rel_mse_sums(filled(2, 2, 1.0f), filled(2, 2, 0.0f));
  ASSERT_TRUE(black.ok());
  EXPECT_EQ(black->global(), 0.0);
  EXPECT_NEAR(black->per_pixel(), 100.0, 1e-9);
}

TEST(ReportErrorMetricsTest, SumsCombineFramesExactly) {
  auto a = rel_mse_sums(filled(2, 2, 2.0f), filled(2, 2, 1.0f));   // error 1, energy 1 per value
  auto b = rel_mse_sums(filled(2, 2, 1.0f), filled(2, 2, 1.0f));   // no error
  ASSERT_TRUE(a.ok() && b.ok());
  RelMseSums t = a.value();
  t.add(b.value());
  EXPECT_DOUBLE_EQ(t.global(), 0.5);
  EXPECT_NEAR(t.per_pixel(), 0.5 / 1.01, 1e-12);
}

TEST(ReportErrorMetricsTest, NonFiniteValuesAreCountedNotHidden) {
  Image img = filled(2, 1, 1.0f);
  img.at(0, 0, 1) = std::nanf("");
  img.at(1, 0, 2) = INFINITY;
  auto s = rel_mse_sums(img, filled(2, 1, 1.0f));
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->non_finite, 2);
  EXPECT_TRUE(std::isfinite(s->global()));
  EXPECT_NEAR(s->global(), 2.0 / 6.0, 1e-12);  // each counts as black: error 1
}

TEST(ReportErrorMetricsTest, SizeMismatchNamesBothSizes) {
  auto s = rel_mse_sums(filled(2, 2, 1.0f), filled(3, 2, 1.0f));
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.status().message().find("2x2x3"), std::string::npos);
  EXPECT_NE(s.status().message().find("3x2x3"), std::string::npos);
  EXPECT_FALSE(rel_mse_sums(Image(2, 2, 1), Image(2, 2, 1)).ok());
}

TEST(ReportErrorMetricsTest, FlickerIgnoresStaticBiasAndMeasuresChange) {
  const Image r0 = filled(4, 4, 0.5f), r1 = filled(4, 4, 0.7f), r2 = filled(4, 4, 0.2f);
  // Constant error +0.1 on a changing reference: no flicker.
  const Image b0 = filled(4, 4, 0.6f), b1 = filled(4, 4, 0.8f), b2 = filled(4, 4, 0.3f);
  auto f0 = temporal_flicker({&b0, &b1, &b2}, {&r0, &r1, &r2});
  ASSERT_TRUE(f0.ok()) << f0.status().to_string();
  EXPECT_NEAR(f0.value(), 0.0, 1e-12);
  // Error alternating +a, −a, +a: every step changes it by 2a -> (2a)².
  const float a = 0.05f;
  const Image n0 = filled(4, 4, 0.5f + a), n1 = filled(4, 4, 0.7f - a), n2 = filled(4, 4, 0.2f + a);
  auto f1 = temporal_flicker({&n0, &n1, &n2}, {&r0, &r1, &r2});
  ASSERT_TRUE(f1.ok());
  EXPECT_NEAR(f1.value(), 4.0 * a * a, 1e-7);
  // One step of change out of two: half of it.
  const Image h2 = filled(4, 4, 0.2f - a);
  auto f2 = temporal_flicker({&n0, &n0, &h2}, {&r0, &r0, &r2});
  ASSERT_TRUE(f2.ok());
  EXPECT_NEAR(f2.value(), 0.5 * 4.0 * a * a, 1e-7);
}

TEST(ReportErrorMetricsTest, FlickerRejectsShortOrMismatchedSequences) {
  const Image r = filled(2, 2, 1.0f), s = filled(3, 2, 1.0f);
  EXPECT_FALSE(temporal_flicker({&r}, {&r}).ok());
  EXPECT_FALSE(temporal_flicker({&r, &r}, {&r}).ok());
  EXPECT_FALSE(temporal_flicker({&r, &s}, {&r, &s}).ok());
}

TEST(ReportErrorMetricsTest, MeanFiniteSkipsNaN) {
  Image im(2, 2, 1);
  im.at(0, 0, 0) = 1.0f;
  im.at(1, 0, 0) = 0.0f;
  im.at(0, 1, 0) = 0.5f;
  im.at(1, 1, 0) = std::nanf("");
  EXPECT_DOUBLE_EQ(mean_finite(im), 0.5);
  EXPECT_DOUBLE_EQ(mean_finite(Image()), 0.0);
}

TEST(ReportErrorMetricsTest, LogLogInterpolationIsExactOnPowerLaws) {
  // relMSE ∝ 1/t: (1, 1), (4, 0.25) -> 0.5 at t = 2.
  std::vector<std::pair<double, double>> pts = {{4.0, 0.25}, {1.0, 1.0}};
  EXPECT_NEAR(interpolate_log_log(pts, 2.0), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(interpolate_log_log(pts, 4.0), 0.25);
  // Short extrapolation along the end segment (factor <= 1.25), none beyond.
  EXPECT_NEAR(interpolate_log_log(pts, 4.8), 0.25 * 4.0 / 4.8, 1e-12);
  EXPECT_NEAR(interpolate_log_log(pts, 0.9), 1.0 / 0.9, 1e-12);
  EXPECT_TRUE(std::isnan(interpolate_log_log(pts, 0.5)));
  EXPECT_TRUE(std::isnan(interpolate_log_log(pts, 5.5)));
  EXPECT_TRUE(std::isnan(interpolate_log_log({}, 1.0)));
  EXPECT_TRUE(std::isnan(interpolate_log_log({{1.0, 1.0}}, 1.1)));
  EXPECT_DOUBLE_EQ(interpolate_log_log({{1.0, 1.0}}, 1.0), 1.0);
  // Three points: the middle segment is used between them.
  EXPECT_NEAR(interpolate_log_log({{1.0, 1.0}, {2.0, 0.5}, {4.0, 0.5}}, 3.0), 0.5, 1e-12);
  // Non-positive values are ignored, not logged.
  EXPECT_NEAR(interpolate_log_log({{1.0, 1.0}, {2.0, 0.0}, {4.0, 0.25}}, 2.0), 0.5, 1e-12);
}

}  // namespace
}  // namespace gdvr
