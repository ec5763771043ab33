// gdvr's own single-precision exp, log, erf and erfc, for the microfacet
// code (microfacet.cpp, beckmann_slope.cpp).
//
// Why not libm: a vector kernel that shades eight paths at once must round
// exactly as the scalar code does, so that a path's image does not depend on
// which of them ran it (diffuse_batch.h). glibc's expf, logf and erff have
// no vector twins with their bits. These are short polynomial forms (Cephes'
// expf, logf, erff and erfcf coefficients, S. L. Moshier) that a kernel can
// repeat operation for operation; tests/core/math/elementary_test.cpp bounds
// their error against long double (about 2 ulp for exp and log, 2e-7
// relative for erf and erfc) and checks the special values.
//
// Every step is a plain float operation in a fixed order: the build sets
// -ffp-contract=off, so nothing is fused differently in the scalar and
// vector forms.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

namespace gdvr {
namespace elementary {

inline float from_bits(uint32_t b) {
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}
inline uint32_t to_bits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

constexpr float kExpMax = 88.7228317f;   // above: overflow
constexpr float kExpMin = -104.0f;       // below: 0 (exp(-104) < 2^-150)
constexpr float kLog2e = 1.44269504088896341f;
constexpr float kLn2Hi = 0.693359375f;   // ln 2 = kLn2Hi + kLn2Lo, kLn2Hi short
constexpr float kLn2Lo = -2.12194440e-4f;
constexpr float kSqrtHalf = 0.707106781186547524f;
constexpr float kMinNormal = 1.17549435e-38f;

// The polynomials' coefficients, highest degree first (Horner's order),
// shared with the vector kernels' own loops over them.
// exp: 1 + r + r^2 P(r) on r in [-ln2/2, ln2/2].
constexpr float kExpPoly[] = {1.9875691500e-4f, 1.3981999507e-3f, 8.3334519073e-3f,
                              4.1665795894e-2f, 1.6666665459e-1f, 5.0000001201e-1f};
// log: log(1 + x) = x - x^2 / 2 + x^3 P(x) on 1 + x in [sqrt(1/2), sqrt(2)).
constexpr float kLogPoly[] = {7.0376836292e-2f,  -1.1514610310e-1f, 1.1676998740e-1f,
                              -1.2420140846e-1f, 1.4249322787e-1f,  -1.6668057665e-1f,
                              2.0000714765e-1f,  -2.4999993993e-1f, 3.3333331174e-1f};
// erf(x) = x T(x^2) on |x| <= 1.
constexpr float kErfPoly[] = {7.853861353153693e-5f,  -8.010193625184903e-4f, 5.188327685732524e-3f,
                              -2.685381193529856e-2f, 1.128358514861418e-1f,  -3.761262582423300e-1f,
                              1.128379165726710e+0f};
// erfc(x) = exp(-x^2) / x P(1 / x^2) on 1 <= x < 2, and R(1 / x^2) beyond.
constexpr float kErfcNearPoly[] = {2.326819970068386e-2f,  -1.387039388740657e-1f, 3.687424674597105e-1f,
                                   -5.824733027278666e-1f, 6.210004621745983e-1f,  -4.944515323274145e-1f,
                                   3.404879937665872e-1f,  -2.741127028184656e-1f, 5.638259427386472e-1f};
constexpr float kErfcFarPoly[] = {-1.047766399936249e+1f, 1.297719955372516e+1f,  -7.495518717768503e+0f,
                                  2.921019019210786e+0f,  -1.015265279202700e+0f, 4.218463358204948e-1f,
                                  -2.820767439740514e-1f, 5.641895067754075e-1f};

template <size_t N>
inline float horner(const float (&c)[N], float x) {
  float p = c[0];
  for (size_t i = 1; i < N; ++i) p = p * x + c[i];
  return p;
}

}  // namespace elementary

// e^x; 0 below -104, +inf above ln(FLT_MAX), NaN for NaN.
inline float exp_f(float x) {
  using namespace elementary;
  if (!(x >= kExpMin)) return x < kExpMin ? 0.0f : x;  // NaN stays NaN
  if (x > kExpMax) return std::numeric_limits<float>::infinity();
  const float n = std::floor(x * kLog2e + 0.5f);
  const float r = (x - n * kLn2Hi) - n * kLn2Lo;
  const float p = horner(kExpPoly, r) * (r * r) + r + 1.0f;
  // 2^n as two factors that are both normal floats, so that results in the
  // subnormal range round once (the first product is exact).
  const int32_t ni = int32_t(n), half = ni >> 1;
  return p * from_bits(uint32_t(half + 127) << 23) * from_bits(uint32_t(ni - half + 127) << 23);
}

// The natural logarithm; -inf at 0, NaN below 0 and for NaN, +inf at +inf.
inline float log_f(float x) {
  using namespace elementary;
  if (!(x > 0.0f)) return x == 0.0f ? -std::numeric_limits<float>::infinity()
                                    : std::numeric_limits<float>::quiet_NaN();
  if (x == std::numeric_limits<float>::infinity()) return x;
  float e_shift = 0.0f;
  if (x < kMinNormal) {  // subnormal: make it normal first
    x *= 33554432.0f;    // 2^25
    e_shift = -25.0f;
  }
  const uint32_t bits = to_bits(x);
  // x = m 2^e with m in [0.5, 1).
  float e = float(int32_t(bits >> 23) - 126) + e_shift;
  float m = from_bits((bits & 0x007fffffu) | 0x3f000000u);
  if (m < kSqrtHalf) {
    e = e - 1.0f;
    m = m + m - 1.0f;
  } else {
    m = m - 1.0f;
  }
  float y = horner(kLogPoly, m) * m * (m * m);
  y = y + e * kLn2Lo;
  y = y - 0.5f * (m * m);
  return (m + y) + e * kLn2Hi;
}

// erfc(x) for x >= 1 (0 once exp(-x^2) is).
inline float erfc_large(float x) {
  using namespace elementary;
  const float e = exp_f(-(x * x));
  const float q = 1.0f / x;
  const float t = q * q;
  const float p = x < 2.0f ? horner(kErfcNearPoly, t) : horner(kErfcFarPoly, t);
  return e * q * p;
}

// The error function.
inline float erf_f(float x) {
  const float a = std::abs(x);
  if (!(a > 1.0f)) return x * elementary::horner(elementary::kErfPoly, x * x);  // NaN too
  return std::copysign(1.0f - erfc_large(a), x);
}

// The complementary error function 1 - erf(x), accurate relative to itself
// for large x (the Smith G1 of microfacet.cpp needs that).
inline float erfc_f(float x) {
  const float a = std::abs(x);
  if (!(a >= 1.0f)) return 1.0f - x * elementary::horner(elementary::kErfPoly, x * x);  // NaN too
  const float y = erfc_large(a);
  return x < 0.0f ? 2.0f - y : y;
}

}  // namespace gdvr
