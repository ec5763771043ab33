#include <cmath>
#include <limits>

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
      if (want_sin > 0 && want_sin < 1e-2) {
        ASSERT_NEAR(c.sin_c / double(want_sin), 1.0, 1e-4) << sin_alpha << " " << u;
      }
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

// The cone's pdf, 1 / (2 pi (1 - cos alpha)), from a light 1e-20 of its
// distance across to one almost touching: relative accuracy of float.
TEST(SphereConeTest, PdfMatchesLongDouble) {
  for (double dist2 : {1e-6, 1.0, 1e8}) {
    for (long double sin2_alpha : {1e-40L, 1e-12L, 1e-4L, 0.0625L, 0.5L, 0.99L, 1.0L / (1.0L + 1e-5L)}) {
      const double r2 = double(sin2_alpha * dist2);
      const long double s = (long double)r2 / (long double)dist2;
      const long double one_minus_cos = s / (1 + std::sqrt(1 - s));
      const long double want = 1 / (2 * 3.14159265358979323846264L * one_minus_cos);
      const float pdf = sphere_cone_pdf(dist2, r2);
      if (want > (long double)std::numeric_limits<float>::max()) {
        EXPECT_TRUE(std::isinf(pdf)) << dist2 << " " << double(sin2_alpha);
        continue;
      }
      EXPECT_NEAR(double(pdf / want), 1.0, 3e-7) << dist2 << " " << double(sin2_alpha);
    }
  }
}

}  // namespace
}  // namespace gdvr
