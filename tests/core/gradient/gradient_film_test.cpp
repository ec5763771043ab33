// The gradient film's conventions: dx(p) = right(p) + left(p + e_x),
// dy(p) = down(p) + up(p + e_y), means over spp, variances from the halves,
// failure rates per pixel.
#include <gtest/gtest.h>

#include "core/gradient/gradient_film.h"

namespace gdvr {
namespace {

TEST(GradientFilmTest, CombinesBothGenerationsOfAPairAndMeasuresVariance) {
  GradientFilm film(2, 2);
  for (uint32_t s = 0; s < 2; ++s) {
    GradientSample a;
    a.primal = Rgb(s == 0 ? 1.0f : 3.0f);
    a.gradient[size_t(OffsetDir::kRight)] = Rgb(0.25f);
    a.gradient[size_t(OffsetDir::kDown)] = Rgb(0.5f);
    a.shifts = 2;
    a.failures = s == 0 ? 1 : 0;
    film.add(0, 0, s, a);
    GradientSample b;
    b.gradient[size_t(OffsetDir::kLeft)] = Rgb(0.75f);
    film.add(1, 0, s, b);
    GradientSample c;
    c.gradient[size_t(OffsetDir::kUp)] = Rgb(-0.5f);
    film.add(0, 1, s, c);
  }
  GradientFilmBuffers out = film.resolve(2);
  EXPECT_FLOAT_EQ(out.primal.at(0, 0, 0), 2.0f);
  EXPECT_FLOAT_EQ(out.dx.at(0, 0, 1), 1.0f);  // 0.25 + 0.75
  EXPECT_FLOAT_EQ(out.dy.at(0, 0, 2), 0.0f);  // 0.5 - 0.5
  EXPECT_FLOAT_EQ(out.dx.at(1, 0, 0), 0.0f);  // no constraint beyond the last column
  // Halves 1 and 3: s² = (1-3)² / (1 + 1) = 2, variance of the mean of 2 = 1.
  EXPECT_FLOAT_EQ(out.primal_var.at(0, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(out.dx_var.at(0, 0, 0), 0.0f);
  EXPECT_FLOAT_EQ(out.shift_failure_rate.at(0, 0, 0), 0.25f);
}

}  // namespace
}  // namespace gdvr
