#include <cmath>

#include <gtest/gtest.h>

#include "core/math/sampling.h"

namespace gdvr {
namespace {

// The angle at the centre, in long double from the same construction.
long double reference_cos_c(long double sin2_alpha, long double u) {
  const long double omc_alpha = sin2_alpha / (1 + std::sqrt(1 - sin2_alpha));
  const long double omc = u * omc_alpha, sin2 = omc * (2 - omc), cos_theta = 1 - omc;
  const long double sin_max = std::sqrt(sin2_alpha);
  return sin2 / sin_max + cos_theta * std::sqrt(std::max<long double>(0, 1 - sin2 / sin2_alpha));
}

// Both branches (float below sin^2 alpha = 1/16, double above) against long
// double, from a light 1e-4 of its distance across to one at 1.01 radii.
TEST(SphereConeTest, AngleAtTheCentreMatchesLongDouble) {
  int checked = 0;
  for (float sin_alpha : {1e-4f, 3e-3f, 0.05f, 0.2f, 0.249f, 0.251f, 0.5f, 0.9f, 0.99f}) {
    const float sin2_alpha = sin_alpha * sin_alpha;
    for (int i = 0; i <= 1000; ++i) {
      const float u = float(i) / 1000.0f;
      const SphereConePoint c = sphere_point_in_cone(sin2_alpha, u);
      const long double want_cos = reference_cos_c(sin2_alpha, u);
      const long double want_sin = std::sqrt(std::max<long double>(0, 1 - want_cos * want_cos));
      // Within 3e-7 radii plus what 4 ulps of u itself move the point: at the
      // silhouette (u -> 1) the map is steep, and the rounding of x there is
      // worth a few ulps of u.
      const long double du = 4.0L * std::ldexp(1.0L, -24);
      const long double slope = std::abs(reference_cos_c(sin2_alpha, std::min<long double>(1, u + du)) -
                                         reference_cos_c(sin2_alpha, std::max<long double>(0, u - du)));
      const double tolerance = 3e-7 + double(slope);
      ASSERT_NEAR(c.cos_c, double(want_cos), tolerance) << sin_alpha << " " << u;
      // sin c is where cancellation would show (c small, near the pole facing
      // the reference point): relative accuracy there.
      ASSERT_NEAR(c.sin_c, double(want_sin), 2e-6 * double(want_sin) + tolerance) << sin_alpha << " " << u;
      if (want_sin > 0 && want_sin < 1e-2) ASSERT_NEAR(c.sin_c / double(want_sin), 1.0, 1e-4) << sin_alpha << " " << u;
      ASSERT_NEAR(double(c.sin_c) * c.sin_c + double(c.cos_c) * c.cos_c, 1.0, 1e-6);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 9 * 1001);
}

// The cone's edge (u = 1) is the sphere's silhouette: c = 90 deg - alpha.
TEST(SphereConeTest, TheConeEdgeLandsOnTheSilhouette) {
  for (float sin_alpha : {1e-3f, 0.1f, 0.24f, 0.6f}) {
    const SphereConePoint c = sphere_point_in_cone(sin_alpha * sin_alpha, 1.0f);
    EXPECT_NEAR(c.cos_c, sin_alpha, 2e-6f * sin_alpha + 1e-7f) << sin_alpha;
  }
}

}  // namespace
}  // namespace gdvr
