// Jakob 2014, "An improved visible normal sampling routine for the Beckmann
// distribution": the slope of a visible normal of the alpha = 1 Beckmann
// distribution, by Newton's method on the slope CDF in the erf() domain
// (three steps from an analytic first guess, as Mitsuba 3).
//
// It is a value that takes one step at a time so that a batch of paths can
// take each step for all of its samples in one loop (path_batch.cpp). One
// inversion is a chain of about fifteen dependent transcendental calls, so
// it is bound by their latency, not by instruction count: run one after the
// other, inversions cost ~140 ns each on the development machine; stepped
// side by side, ~75 ns, with the same bits (docs/bsdf.md).
#pragma once

#include "core/math/vec.h"

namespace gdvr {

class BeckmannSlopeInversion {
 public:
  static constexpr int kNewtonSteps = 3;

  BeckmannSlopeInversion() = default;
  // The inversion for incidence cos_theta_i (in the stretched, alpha = 1
  // space) and the sample's two numbers u; computes the first guess.
  BeckmannSlopeInversion(float cos_theta_i, Vec2f u);

  void newton_step();
  // The slope after kNewtonSteps steps: {along the incidence azimuth, across it}.
  Vec2f slope() const;

  // The three parts in one call.
  static Vec2f solve(float cos_theta_i, Vec2f u) {
    BeckmannSlopeInversion inv(cos_theta_i, u);
    for (int i = 0; i < kNewtonSteps; ++i) inv.newton_step();
    return inv.slope();
  }

 private:
  float x_ = 0;            // the iterate, erf(slope)
  float target_ = 0;       // u.x scaled by the CDF's normalisation
  float tan_theta_i_ = 0;
  float u_y_ = 0;          // the second number, clamped
};

}  // namespace gdvr
