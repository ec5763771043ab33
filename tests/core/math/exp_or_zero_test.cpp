// exp_or_zero (vec.h) skips the call only where std::exp's float result is 0:
// bit for bit equal to std::exp over the whole range where it underflows and
// around its threshold, every float in [-110, -80] and a sweep beyond.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "core/math/vec.h"

namespace gdvr {
namespace {

uint32_t bits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

TEST(ExpOrZero, SameBitsAsStdExpAroundTheUnderflow) {
  int zeros = 0, subnormals = 0, checked = 0;
  for (float x = -110.0f; x <= -80.0f; x = std::nextafter(x, 0.0f)) {
    const float want = std::exp(x);
    ASSERT_EQ(bits(exp_or_zero(x)), bits(want)) << "x = " << x;
    zeros += want == 0.0f;
    subnormals += want > 0.0f && want < std::numeric_limits<float>::min();
    ++checked;
  }
  // The range covers both sides of the shortcut: results of exactly 0 (below
  // ~-103.97) and subnormal results (which still take the call).
  EXPECT_GT(zeros, 100000);
  EXPECT_GT(subnormals, 100000);
  EXPECT_GT(checked, 1000000);
}

TEST(ExpOrZero, SameBitsAsStdExpElsewhere) {
  for (float x : {-std::numeric_limits<float>::infinity(), -1e30f, -1000.0f, -104.0f, -1.0f, -0.0f, 0.0f, 1e-8f, 1.0f,
                  88.0f, 100.0f, std::numeric_limits<float>::infinity()})
    EXPECT_EQ(bits(exp_or_zero(x)), bits(std::exp(x))) << "x = " << x;
  EXPECT_TRUE(std::isnan(exp_or_zero(std::numeric_limits<float>::quiet_NaN())));
}

}  // namespace
}  // namespace gdvr
