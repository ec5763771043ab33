#include "core/math/sincos.h"

#include <cmath>

#include <gtest/gtest.h>

namespace gdvr {
namespace {

// Distance in units of float spacing at the value (ulp), against the double result.
double ulps(float got, double want) {
  const double spacing = std::ldexp(1.0, std::ilogb(std::max(std::abs(want), 1e-30)) - 23);
  return std::abs(double(got) - want) / spacing;
}

TEST(SinCosTest, TurnsMatchLibmOnTheUnitIntervalAndBeyond) {
  double worst_abs = 0;
  for (int i = -200000; i <= 600000; ++i) {
    const float t = float(i) / 400000.0f;  // [-0.5, 1.5] turns, through every quadrant boundary
    const SinCos r = sincos_turns(t);
    const double a = 2.0 * M_PI * double(t);
    worst_abs = std::max({worst_abs, std::abs(double(r.sin) - std::sin(a)), std::abs(double(r.cos) - std::cos(a))});
    // Near zeros the absolute error is what matters (the argument's own rounding dominates).
    if (std::abs(std::sin(a)) > 0.1) ASSERT_LE(ulps(r.sin, std::sin(a)), 3.0) << "t = " << t;
    if (std::abs(std::cos(a)) > 0.1) ASSERT_LE(ulps(r.cos, std::cos(a)), 3.0) << "t = " << t;
  }
  EXPECT_LT(worst_abs, 2.5e-7);
}

TEST(SinCosTest, ExactAtQuarterTurnsAndUnitLength) {
  const float want_sin[] = {0, 1, 0, -1, 0}, want_cos[] = {1, 0, -1, 0, 1};
  for (int q = 0; q <= 4; ++q) {
    const SinCos r = sincos_turns(0.25f * float(q));
    EXPECT_NEAR(r.sin, want_sin[q], 1e-7f) << q;
    EXPECT_NEAR(r.cos, want_cos[q], 1e-7f) << q;
  }
  for (float t = 0.0f; t < 1.0f; t += 0.0013f) {
    const SinCos r = sincos_turns(t);
    EXPECT_NEAR(double(r.sin) * r.sin + double(r.cos) * r.cos, 1.0, 4e-7) << t;
  }
}

TEST(SinCosTest, EighthTurnMatchesLibm) {
  for (int i = -1000; i <= 1000; ++i) {
    const float x = float(i) / 1000.0f * float(M_PI / 4);
    const SinCos r = sincos_eighth_turn(x);
    EXPECT_NEAR(r.sin, std::sin(double(x)), 1.2e-7) << x;
    EXPECT_NEAR(r.cos, std::cos(double(x)), 1.2e-7) << x;
  }
}

}  // namespace
}  // namespace gdvr
