// gdvr's own exp, log, erf and erfc (core/math/elementary.h) against long
// double: every float in the ranges the microfacet code uses them on, their
// error in ulp (exp, log) or relative (erf, erfc), and the special values.
#include "core/math/elementary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace gdvr {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// |got - want| in units of the float spacing at want (subnormals: the
// smallest spacing).
double ulps(float got, long double want) {
  const float w = float(want);
  const float spacing = std::nextafter(std::abs(w), kInf) - std::abs(w);
  return double(std::abs((long double)got - want) / (long double)spacing);
}

// Every `stride`-th float in [lo, hi], in order (stepping the bit patterns:
// negative floats are ordered by their bits reversed).
int64_t ordered(float x) {
  const int64_t b = int64_t(elementary::to_bits(x));
  return b & 0x80000000 ? -(b & 0x7fffffff) : b;
}
float unordered(int64_t k) { return elementary::from_bits(k < 0 ? uint32_t(-k) | 0x80000000u : uint32_t(k)); }
template <class F>
void for_floats(float lo, float hi, int stride, F f) {
  for (int64_t k = ordered(lo); k <= ordered(hi); k += stride) f(unordered(k));
}

TEST(ElementaryTest, ExpWithinTwoUlpOverItsWholeRange) {
  double worst = 0, worst_subnormal = 0;
  long checked = 0;
  for_floats(-104.0f, 88.72f, 101, [&](float x) {
    const long double want = std::exp((long double)x);
    const double e = ulps(exp_f(x), want);
    if (want < (long double)std::numeric_limits<float>::min()) worst_subnormal = std::max(worst_subnormal, e);
    else worst = std::max(worst, e);
    ++checked;
  });
  EXPECT_GT(checked, 1000000);
  EXPECT_LT(worst, 2.0);
  // Subnormal results are rounded once, from a product that was exact.
  EXPECT_LE(worst_subnormal, 1.0);
}

TEST(ElementaryTest, ExpSpecialValues) {
  EXPECT_EQ(exp_f(0.0f), 1.0f);
  EXPECT_EQ(exp_f(-0.0f), 1.0f);
  EXPECT_EQ(exp_f(-104.5f), 0.0f);
  EXPECT_EQ(exp_f(-1e30f), 0.0f);
  EXPECT_EQ(exp_f(-kInf), 0.0f);
  EXPECT_EQ(exp_f(88.8f), kInf);
  EXPECT_EQ(exp_f(kInf), kInf);
  EXPECT_TRUE(std::isnan(exp_f(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_GT(exp_f(-103.9f), 0.0f);  // subnormal, not flushed
  EXPECT_LT(exp_f(88.72f), kInf);
}

TEST(ElementaryTest, LogWithinTwoUlpForEveryPositiveFloat) {
  double worst = 0;
  long checked = 0;
  for_floats(std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max(), 1009, [&](float x) {
    worst = std::max(worst, ulps(log_f(x), std::log((long double)x)));
    ++checked;
  });
  EXPECT_GT(checked, 2000000);
  EXPECT_LT(worst, 2.0);
  EXPECT_EQ(log_f(1.0f), 0.0f);
  EXPECT_FALSE(std::signbit(log_f(1.0f)));
  EXPECT_EQ(log_f(0.0f), -kInf);
  EXPECT_EQ(log_f(-0.0f), -kInf);
  EXPECT_EQ(log_f(kInf), kInf);
  EXPECT_TRUE(std::isnan(log_f(-1.0f)));
  EXPECT_TRUE(std::isnan(log_f(std::numeric_limits<float>::quiet_NaN())));
}

TEST(ElementaryTest, ErfAndErfcRelativeErrors) {
  double worst_erf = 0, worst_erfc = 0;
  for_floats(-12.0f, 12.0f, 1013, [&](float x) {
    const long double e = std::erf((long double)x), c = std::erfc((long double)x);
    // Relative where x (and erf x ~ 1.13 x) is far from the subnormals.
    if (std::abs(x) > 1e-30f) worst_erf = std::max(worst_erf, double(std::abs((erf_f(x) - e) / e)));
    // erfc relative to itself where it is a normal float (x < ~9.2).
    if (c > (long double)std::numeric_limits<float>::min())
      worst_erfc = std::max(worst_erfc, double(std::abs((erfc_f(x) - c) / c)));
  });
  EXPECT_LT(worst_erf, 3e-7);
  // exp(-x^2) from the rounded square: the error grows as x^2 ulp of it
  // (5e-6 at x = 9); the Smith G1 (microfacet.cpp) takes exp(-a^2) from the
  // same square, so the two terms it subtracts share it.
  EXPECT_LT(worst_erfc, 8e-6);
  // Below x = 1, erfc is 1 - erf: erf's 2.6e-7 (at x = 0.99) grows by 1 / erfc(1) = 6.4.
  double worst_erfc_small = 0;
  for_floats(-2.0f, 2.0f, 211, [&](float x) {
    const long double c = std::erfc((long double)x);
    worst_erfc_small = std::max(worst_erfc_small, double(std::abs((erfc_f(x) - c) / c)));
  });
  EXPECT_LT(worst_erfc_small, 1.2e-6);
  EXPECT_EQ(erf_f(0.0f), 0.0f);
  EXPECT_EQ(erf_f(kInf), 1.0f);
  EXPECT_EQ(erf_f(-kInf), -1.0f);
  EXPECT_EQ(erfc_f(kInf), 0.0f);
  EXPECT_EQ(erfc_f(-kInf), 2.0f);
  EXPECT_EQ(erfc_f(0.0f), 1.0f);
  EXPECT_TRUE(std::isnan(erf_f(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_TRUE(std::isnan(erfc_f(std::numeric_limits<float>::quiet_NaN())));
}

}  // namespace
}  // namespace gdvr
