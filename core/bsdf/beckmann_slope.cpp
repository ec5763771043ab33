#include "core/bsdf/beckmann_slope.h"

#include <algorithm>
#include <cmath>

#include "core/bsdf/microfacet.h"
#include "core/math/elementary.h"

namespace gdvr {

BeckmannSlopeInversion::BeckmannSlopeInversion(float cos_theta_i, Vec2f u) {
  tan_theta_i_ = safe_sqrt(1.0f - cos_theta_i * cos_theta_i) / cos_theta_i;
  const float cot_theta_i = 1.0f / tan_theta_i_;
  const float maxval = erf_f(cot_theta_i);
  const float u_x = std::clamp(u.x, 1e-6f, 1.0f - 1e-6f);
  u_y_ = std::clamp(u.y, 1e-6f, 1.0f - 1e-6f);
  x_ = maxval - (maxval + 1.0f) * erf_f(std::sqrt(-log_f(u_x)));
  target_ = u_x * (1.0f + maxval + kInvSqrtPi * tan_theta_i_ * exp_f(-sqr(cot_theta_i)));
}

void BeckmannSlopeInversion::newton_step() {
  const float slope = erfinv(x_);
  const float value = 1.0f + x_ + kInvSqrtPi * tan_theta_i_ * exp_f(-sqr(slope)) - target_;
  const float derivative = 1.0f - slope * tan_theta_i_;
  x_ -= value / derivative;
}

Vec2f BeckmannSlopeInversion::slope() const { return {erfinv(x_), erfinv(2.0f * u_y_ - 1.0f)}; }

}  // namespace gdvr
