// Sine and cosine of angles given in turns (1 turn = 2 pi), for the warps of
// the sampling code. Every sampled direction needs a (sin, cos) pair of an
// azimuth drawn as u in [0, 1); glibc's sincosf handles any argument in any
// rounding mode and cost 2-3 % of PT on cbox and matpreview. Angles in turns
// reduce exactly to the nearest quarter turn, and on the remaining
// [-pi/4, pi/4] the Taylor series to degree 9 (sine) and 10 (cosine) is exact
// to 3e-9, well below float resolution: the results are within 2 ulp of the
// correctly rounded ones (tests/core/math/sincos_test.cpp).
#pragma once

#include <cstdint>
#include <cstring>

#include "core/math/vec.h"

namespace gdvr {

struct SinCos {
  float sin, cos;
};

// (sin x, cos x) for |x| <= pi / 4 (radians).
inline SinCos sincos_eighth_turn(float x) {
  const float x2 = x * x;
  const float s = x * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f)))));
  const float c =
      1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f + x2 * (-1.0f / 3628800.0f)))));
  return {s, c};
}

// (sin 2 pi t, cos 2 pi t) for finite t; accurate for |t| up to about 1e6.
inline SinCos sincos_turns(float t) {
  // The nearest quarter turn k (floor without SSE4.1's roundss), then the rest
  // in [-1/8, 1/8] turns; t - k / 4 is exact for the |t| <= 1 of the warps.
  const float k4 = 4.0f * t + 0.5f;
  int32_t k = int32_t(k4);
  if (float(k) > k4) --k;
  const SinCos r = sincos_eighth_turn((t - float(k) * 0.25f) * (2.0f * kPi));
  // Quadrant k: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s). Selected with
  // bit masks: the quadrant is random, so a branch would mispredict half the time.
  uint32_t s_bits, c_bits;
  std::memcpy(&s_bits, &r.sin, 4);
  std::memcpy(&c_bits, &r.cos, 4);
  const uint32_t swap = 0u - uint32_t(k & 1);
  uint32_t sin_bits = (s_bits & ~swap) | (c_bits & swap), cos_bits = (c_bits & ~swap) | (s_bits & swap);
  sin_bits ^= uint32_t(k & 2) << 30;        // negative in quadrants 2 and 3
  cos_bits ^= uint32_t((k + 1) & 2) << 30;  // negative in quadrants 1 and 2
  SinCos out;
  std::memcpy(&out.sin, &sin_bits, 4);
  std::memcpy(&out.cos, &cos_bits, 4);
  return out;
}

}  // namespace gdvr
