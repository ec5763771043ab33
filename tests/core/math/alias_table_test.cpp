#include "core/math/alias_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace gdvr {
namespace {

// Chi-square of the sampled bin frequencies against the weights, with zero
// weights, a huge range and a non-finite weight; a zero-weight bin is never chosen.
TEST(AliasTableTest, FrequenciesFollowWeights) {
  std::vector<float> w = {1.0f, 0.0f, 3.0f, 1e-3f, 40.0f, std::nanf(""), 0.5f, 2.0f, 0.0f, 7.0f};
  std::vector<AliasSlot> slots;
  const double total = build_alias_table(w.data(), w.size(), &slots);
  ASSERT_EQ(slots.size(), w.size());
  EXPECT_NEAR(total, 53.501, 1e-4);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  const int n = 400000;
  std::vector<double> counts(w.size(), 0.0);
  for (int i = 0; i < n; ++i) {
    AliasSample s = sample_alias(slots.data(), slots.size(), uni(rng));
    ASSERT_LT(s.index, w.size());
    ASSERT_GT(s.pmf, 0.0f) << "bin " << s.index;
    ASSERT_FLOAT_EQ(s.pmf, slots[s.index].pmf);
    counts[s.index] += 1;
  }
  double chi2 = 0;
  int dof = -1;
  for (size_t i = 0; i < w.size(); ++i) {
    const double p = (std::isfinite(w[i]) && w[i] > 0) ? w[i] / total : 0.0;
    EXPECT_FLOAT_EQ(slots[i].pmf, float(p));
    if (p == 0) {
      EXPECT_EQ(counts[i], 0.0) << "zero-weight bin " << i << " was chosen";
      continue;
    }
    const double expected = p * n;
    chi2 += (counts[i] - expected) * (counts[i] - expected) / expected;
    ++dof;
  }
  // 6 degrees of freedom: P(chi2 > 22.46) = 0.001.
  EXPECT_EQ(dof, 6);
  EXPECT_LT(chi2, 22.46);
}

// Within the chosen bin the remapped u is uniform: its mean over many samples
// is 1/2 and its histogram is flat, for bins that own and lend slot fractions.
TEST(AliasTableTest, RemappedUIsUniformWithinTheBin) {
  std::vector<float> w = {1.0f, 5.0f, 0.25f, 2.0f};
  std::vector<AliasSlot> slots;
  build_alias_table(w.data(), w.size(), &slots);
  const int n = 400000, bins = 8;
  std::vector<std::vector<double>> hist(w.size(), std::vector<double>(bins, 0.0));
  std::vector<double> count(w.size(), 0.0);
  for (int i = 0; i < n; ++i) {
    AliasSample s = sample_alias(slots.data(), slots.size(), (float(i) + 0.5f) / float(n));
    ASSERT_GE(s.u_remapped, 0.0f);
    ASSERT_LT(s.u_remapped, 1.0f);
    hist[s.index][size_t(s.u_remapped * bins)] += 1;
    count[s.index] += 1;
  }
  for (size_t b = 0; b < w.size(); ++b) {
    for (int k = 0; k < bins; ++k) EXPECT_NEAR(hist[b][size_t(k)] / count[b], 1.0 / bins, 2e-3) << b << " " << k;
  }
}

TEST(AliasTableTest, AllZeroWeightsGiveZeroPmf) {
  std::vector<float> w = {0.0f, 0.0f, -1.0f};
  std::vector<AliasSlot> slots;
  EXPECT_EQ(build_alias_table(w.data(), w.size(), &slots), 0.0);
  ASSERT_EQ(slots.size(), 3u);
  EXPECT_EQ(sample_alias(slots.data(), slots.size(), 0.4f).pmf, 0.0f);
  EXPECT_EQ(sample_alias(slots.data(), 0, 0.4f).pmf, 0.0f);
}

}  // namespace
}  // namespace gdvr
