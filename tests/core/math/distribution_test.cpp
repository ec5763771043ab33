#include "core/math/distribution.h"

#include <gtest/gtest.h>

namespace gdvr {
namespace {

TEST(DistributionTest, OneDimensionalFrequenciesFollowWeights) {
  Distribution1D d({1.0f, 0.0f, 3.0f, 4.0f});
  std::vector<int> counts(4, 0);
  const int n = 80000;
  for (int i = 0; i < n; ++i) counts[d.sample((float(i) + 0.5f) / n)]++;
  EXPECT_EQ(counts[1], 0);
  EXPECT_NEAR(counts[0] / double(n), 0.125, 1e-3);
  EXPECT_NEAR(counts[3] / double(n), 0.5, 1e-3);
  EXPECT_FLOAT_EQ(d.pmf(2), 0.375f);
}

TEST(DistributionTest, EmptyOrNonFiniteWeightsAreSafe) {
  EXPECT_TRUE(Distribution1D({0.0f, 0.0f}).empty());
  Distribution1D d({std::nanf(""), 2.0f});
  EXPECT_EQ(d.sample(0.0f), 1u);
}

TEST(DistributionTest, TwoDimensionalPdfMatchesSampling) {
  std::vector<float> w = {1, 2, 0, 5, 1, 1};  // 3 x 2
  Distribution2D d(w, 3, 2);
  float pdf;
  for (float u : {0.1f, 0.5f, 0.93f}) {
    Vec2f p = d.sample({u, 0.7f}, &pdf);
    EXPECT_FLOAT_EQ(pdf, d.pdf(p));
    EXPECT_GT(pdf, 0.0f);
  }
  // Density integrates to one over the unit square.
  double integral = 0;
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) integral += d.pdf({(x + 0.5f) / 3, (y + 0.5f) / 2}) / 6.0;
  EXPECT_NEAR(integral, 1.0, 1e-5);
}

}  // namespace
}  // namespace gdvr
