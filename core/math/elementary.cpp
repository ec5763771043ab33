#include "core/math/elementary.h"

#include <cmath>
#include <limits>

namespace gdvr {

[[gnu::noinline]] float exp_f(float x) {
  using namespace elementary;
  if (!(x >= kExpMin && x <= kExpMax)) {
    if (x > kExpMax) return std::numeric_limits<float>::infinity();
    return x < kExpMin ? 0.0f : x;  // NaN stays NaN
  }
  const float shifted = x * kLog2e + kRoundMagic;
  const float n = shifted - kRoundMagic;  // x log2 e, rounded to an integer
  const int32_t ni = int32_t(to_bits(shifted) - kRoundMagicBits);
  const float r = (x - n * kLn2Hi) - n * kLn2Lo;
  const float p = polynomial(kExpPoly, r) * (r * r) + r + 1.0f;
  // 2^n as two factors that are both normal floats, so that results in the
  // subnormal range round once (the first product is exact).
  const int32_t half = ni >> 1;
  return p * from_bits(uint32_t(half + 127) << 23) * from_bits(uint32_t(ni - half + 127) << 23);
}

namespace {

// log_f for x = m 2^e, m in [0.5, 1) from x's bits; e_shift is added to e.
inline float log_of_normal(float x, float e_shift) {
  using namespace elementary;
  const uint32_t bits = to_bits(x);
  float e = float(int32_t(bits >> 23) - 126) + e_shift;
  float m = from_bits((bits & 0x007fffffu) | 0x3f000000u);
  if (m < kSqrtHalf) {
    e = e - 1.0f;
    m = m + m - 1.0f;
  } else {
    m = m - 1.0f;
  }
  float y = polynomial(kLogPoly, m) * m * (m * m);
  y = y + e * kLn2Lo;
  y = y - 0.5f * (m * m);
  return (m + y) + e * kLn2Hi;
}

}  // namespace

[[gnu::noinline]] float log_f(float x) {
  using namespace elementary;
  if (x >= kMinNormal && x < std::numeric_limits<float>::infinity()) return log_of_normal(x, 0.0f);
  if (x == std::numeric_limits<float>::infinity()) return x;
  if (x > 0.0f) return log_of_normal(x * 33554432.0f, -25.0f);  // subnormal: scaled by 2^25 first
  return x == 0.0f ? -std::numeric_limits<float>::infinity() : std::numeric_limits<float>::quiet_NaN();
}

namespace {

// erfc(x) for x >= 1 (0 once exp(-x^2) is).
float erfc_large(float x) {
  using namespace elementary;
  const float e = exp_f(-(x * x));
  const float q = 1.0f / x;
  const float t = q * q;
  const float p = x < 2.0f ? polynomial(kErfcNearPoly, t) : polynomial(kErfcFarPoly, t);
  return e * q * p;
}

}  // namespace

[[gnu::noinline]] float erf_f(float x) {
  const float a = std::abs(x);
  if (!(a > 1.0f)) return x * elementary::polynomial(elementary::kErfPoly, x * x);  // NaN too
  return std::copysign(1.0f - erfc_large(a), x);
}

[[gnu::noinline]] float erfc_f(float x) {
  const float a = std::abs(x);
  if (!(a >= 1.0f)) return 1.0f - x * elementary::polynomial(elementary::kErfPoly, x * x);  // NaN too
  const float y = erfc_large(a);
  return x < 0.0f ? 2.0f - y : y;
}

}  // namespace gdvr
