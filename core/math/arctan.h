// Arc tangent and arc cosine as fractions of a turn, for the lat-long maps of
// environment emitters and sphere uvs. Every ray that escapes to an
// environment map needs one of each; glibc's atan2f and acosf (branchy, with
// special-case handling for every input class) were 2.5 % of PT's
// instructions on matpreview. Here both reduce to one polynomial: the
// octant reduction puts the ratio a = min(|x|, |y|) / max(|x|, |y|) in [0, 1],
// and atan(a) / 2pi is a P(a^2) with P of degree 7, fitted for minimax
// relative error; in float it is within 3.3e-8 turns of atan(a) / 2pi, and the
// result within 6e-8 turns of the exact one after the octant's 1/4 - t and
// 1/2 - t round (about one float spacing there: tests/core/math/arctan_test.cpp).
#pragma once

#include <algorithm>
#include <cmath>

namespace gdvr {

// atan2(y, x) / 2pi in [-1/2, 1/2] for finite x, y, with atan2's quadrant and signed-zero
// conventions (atan2_turns(±0, x < 0) = ±1/2, atan2_turns(0, 0) = 0). NaN in,
// NaN out.
inline float atan2_turns(float y, float x) {
  if (std::isnan(x + y)) return x + y;  // predictable; min/max below would drop the NaN
  const float ax = std::abs(x), ay = std::abs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  const float a = hi > 0.0f ? lo / hi : 0.0f;  // atan2(±0, ±0) as libm
  const float s = a * a;
  float t = a * (0.15915492177009583f +
                 s * (-0.05304967612028122f +
                      s * (0.03178545460104942f +
                           s * (-0.022328631952404976f +
                                s * (0.015824681147933006f +
                                     s * (-0.00953451357781887f +
                                          s * (0.003908644430339336f + s * -0.0007609020103700459f)))))));
  if (ay > ax) t = 0.25f - t;
  if (std::signbit(x)) t = 0.5f - t;
  return std::copysign(t, y);
}

// acos(c) / pi in [0, 1] for c clamped to [-1, 1] (NaN stays NaN), as atan2(sqrt(1 - c^2), c):
// (1 - c)(1 + c) keeps the poles accurate, where 1 - c^2 would cancel.
inline float acos_half_turns(float c) {
  c = std::clamp(c, -1.0f, 1.0f);
  return 2.0f * atan2_turns(std::sqrt((1.0f - c) * (1.0f + c)), c);
}

}  // namespace gdvr
