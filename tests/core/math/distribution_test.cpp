#include "core/math/distribution.h"

#include <gtest/gtest.h>

#include <random>

#include <algorithm>

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

// The cutpoint search picks exactly the bin a binary search over the cdf
// would (std::upper_bound), with runs of zero weights, huge ranges and u near 1.
TEST(DistributionTest, CutpointSearchEqualsBinarySearch) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 1 + int(rng() % 300);
    std::vector<float> w(static_cast<size_t>(n));
    for (float& x : w) {
      const float r = uni(rng);
      x = r < 0.3f ? 0.0f : r < 0.4f ? 1e-6f * uni(rng) : r < 0.45f ? 1e6f * uni(rng) : uni(rng);
    }
    w[size_t(rng() % size_t(n))] = 1.0f;  // at least one positive weight
    Distribution1D d(w);
    std::vector<double> cdf;
    double sum = 0;
    for (float x : w) cdf.push_back(sum += x);
    for (int s = 0; s < 2000; ++s) {
      const float u = s < 4 ? std::vector<float>{0.0f, 0x1.fffffep-1f, 0.5f, 1e-30f}[size_t(s)] : uni(rng);
      size_t expect = size_t(std::upper_bound(cdf.begin(), cdf.end(), double(u) * sum) - cdf.begin());
      expect = std::min(expect, cdf.size() - 1);
      while (w[expect] == 0 && expect > 0) --expect;
      ASSERT_EQ(d.sample(u), expect) << "n " << n << " u " << u;
    }
  }
  EXPECT_EQ(Distribution1D(std::vector<float>{0, 0}).sample(0.5f), 0u);  // empty: in bounds
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
