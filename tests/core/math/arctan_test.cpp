#include "core/math/arctan.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace gdvr {
namespace {

constexpr long double kTwoPi = 6.283185307179586476925286766559L;

TEST(ArctanTest, Atan2TurnsMatchesLongDoubleAroundTheCircle) {
  // Directions all around the circle, and radii from tiny to large (only the
  // ratio matters, so the scale must not).
  double worst = 0;
  for (float radius : {1e-30f, 1e-3f, 1.0f, 7.5f, 1e30f}) {
    for (int i = 0; i < 400000; ++i) {
      const long double angle = kTwoPi * (i + 0.37L) / 400000.0L - kTwoPi / 2;
      const float x = float(radius * std::cos(angle)), y = float(radius * std::sin(angle));
      const long double want = std::atan2((long double)y, (long double)x) / kTwoPi;
      worst = std::max(worst, double(std::abs((long double)atan2_turns(y, x) - want)));
    }
  }
  // The polynomial's 3.3e-8 plus the rounding of 1/4 - t and 1/2 - t (float
  // spacing in [1/4, 1/2) is 3e-8).
  EXPECT_LT(worst, 6e-8);
}

TEST(ArctanTest, Atan2TurnsKeepsLibmsAxesAndSignedZeros) {
  EXPECT_EQ(atan2_turns(0.0f, 1.0f), 0.0f);
  EXPECT_NEAR(atan2_turns(1.0f, 0.0f), 0.25f, 1e-8f);
  EXPECT_NEAR(atan2_turns(-1.0f, 0.0f), -0.25f, 1e-8f);
  EXPECT_EQ(atan2_turns(0.0f, -1.0f), 0.5f);
  EXPECT_EQ(atan2_turns(-0.0f, -1.0f), -0.5f);
  EXPECT_EQ(atan2_turns(0.0f, 0.0f), 0.0f);
  EXPECT_EQ(atan2_turns(0.0f, -0.0f), 0.5f);
  EXPECT_TRUE(std::signbit(atan2_turns(-0.0f, 2.0f)));
  // The diagonals are right to about one float spacing.
  EXPECT_NEAR(atan2_turns(3.0f, 3.0f), 0.125f, 3e-8f);
  EXPECT_NEAR(atan2_turns(3.0f, -3.0f), 0.375f, 3e-8f);
  EXPECT_NEAR(atan2_turns(-3.0f, -3.0f), -0.375f, 3e-8f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(std::isnan(atan2_turns(nan, 1.0f)));
  EXPECT_TRUE(std::isnan(atan2_turns(1.0f, nan)));
}

TEST(ArctanTest, AcosHalfTurnsMatchesLongDoubleUpToThePoles) {
  double worst = 0;
  for (int i = 0; i <= 200000; ++i) {
    const float c = -1.0f + 2.0f * float(i) / 200000.0f;
    const long double want = std::acos((long double)c) / (kTwoPi / 2);
    worst = std::max(worst, double(std::abs((long double)acos_half_turns(c) - want)));
  }
  // Within a few float spacings of the poles, where acos is steepest.
  for (float c = 1.0f; c > 0.9999f; c = std::nextafter(c, 0.0f)) {
    const long double want = std::acos((long double)c) / (kTwoPi / 2);
    worst = std::max(worst, double(std::abs((long double)acos_half_turns(c) - want)));
    const long double want_neg = std::acos((long double)-c) / (kTwoPi / 2);
    worst = std::max(worst, double(std::abs((long double)acos_half_turns(-c) - want_neg)));
  }
  EXPECT_LT(worst, 1.2e-7);
  EXPECT_EQ(acos_half_turns(1.0f), 0.0f);
  EXPECT_EQ(acos_half_turns(-1.0f), 1.0f);
  EXPECT_NEAR(acos_half_turns(0.0f), 0.5f, 1e-8f);
  EXPECT_EQ(acos_half_turns(1.5f), 0.0f);   // clamped, as the callers' old std::clamp
  EXPECT_EQ(acos_half_turns(-7.0f), 1.0f);
  EXPECT_TRUE(std::isnan(acos_half_turns(std::numeric_limits<float>::quiet_NaN())));
}

}  // namespace
}  // namespace gdvr
