// gdvr's own single-precision exp, log, erf and erfc, for the microfacet
// code (microfacet.cpp, beckmann_slope.cpp).
//
// Why not libm: a vector kernel that shades eight paths at once must round
// exactly as the scalar code does, so that a path's image does not depend on
// which of them ran it (vector_batch.h). glibc's expf, logf and erff have
// no vector twins with their bits. These are short polynomial forms (Cephes'
// expf, logf, erff and erfcf coefficients, S. L. Moshier) that a kernel can
// repeat operation for operation; tests/core/math/elementary_test.cpp bounds
// their error against long double (under 2 ulp for exp and log; 3e-7
// relative for erf; for erfc 1.2e-6 below x = 2, growing as x^2 ulp beyond,
// from exp(-x^2) of the rounded square) and checks the special values.
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

// c (highest degree first) at x by Estrin's scheme: pairs of terms, then
// pairs of pairs with x^2, x^4, ...: four dependent multiply-adds for nine
// coefficients instead of Horner's eight, which made the scalar functions
// latency-bound in the path tracer's dependent chains.
//
// Each level is its own fixed-size array with loops of constant trip count,
// so that the compiler keeps every term in a register (with one array and a
// loop over the levels, GCC kept them on the stack, and each multiply-add
// waited on a store and a load).
template <size_t N>
struct Estrin {
  // b lowest degree first, power = x^(2^level).
  static float eval(const float (&b)[N], float power) {
    float next[(N + 1) / 2];
    for (size_t j = 0; j < N / 2; ++j) next[j] = b[2 * j] + b[2 * j + 1] * power;
    if (N % 2 == 1) next[N / 2] = b[N - 1];
    return Estrin<(N + 1) / 2>::eval(next, power * power);
  }
};
template <>
struct Estrin<1> {
  static float eval(const float (&b)[1], float) { return b[0]; }
};

template <size_t N>
inline float polynomial(const float (&c)[N], float x) {
  float b[N];
  for (size_t k = 0; k < N; ++k) b[k] = c[N - 1 - k];  // lowest degree first
  return Estrin<N>::eval(b, x);
}

// exp's argument is rounded to an integer n by adding and subtracting
// 1.5 * 2^23 (exact for |x log2 e| < 2^22), and n read from the sum's bits.
constexpr float kRoundMagic = 12582912.0f;
constexpr uint32_t kRoundMagicBits = 0x4b400000u;

}  // namespace elementary

// Out of line (and not inlined by LTO), as libm's are: inlined, they grew the path batch's loop
// (which inlines the BSDFs) by a seventh and slowed scenes that never call
// them (matpreview 0.973 in 10 paired runs).

// e^x; 0 below -104, +inf above ln(FLT_MAX), NaN for NaN.
float exp_f(float x);
// The natural logarithm; -inf at 0, NaN below 0 and for NaN, +inf at +inf.
float log_f(float x);
// The error function.
float erf_f(float x);
// The complementary error function 1 - erf(x), accurate relative to itself
// for large x (the Smith G1 of microfacet.cpp needs that).
float erfc_f(float x);

}  // namespace gdvr
