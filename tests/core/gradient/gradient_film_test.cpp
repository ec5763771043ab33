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

// The pair primal of pixel p: for each neighbour j, p's own weighted share
// for that pair plus j's offset into p; the mean over the existing neighbours.
TEST(GradientFilmTest, PairPrimalAveragesEachNeighboursPairEstimate) {
  GradientFilm film(3, 1, /* temporal = */ false, /* pair_primal = */ true);
  // Pixel x gets base shares 10x + o (o: direction index) and sends 100x + o
  // into each neighbour; the plain primal is 1 everywhere.
  for (int x = 0; x < 3; ++x) {
    GradientSample s;
    s.primal = Rgb(1.0f);
    for (int o = 0; o < kOffsetCount; ++o) {
      s.pair_base[size_t(o)] = Rgb(float(10 * x + o));
      s.pair_offset[size_t(o)] = Rgb(float(100 * x + o));
    }
    film.add(x, 0, 0, s);
  }
  GradientFilmBuffers out = film.resolve(1);
  ASSERT_FALSE(out.pair_primal.empty());
  const int right = int(OffsetDir::kRight), left = int(OffsetDir::kLeft);
  // x = 0: one neighbour (right, x = 1, whose left offset points back).
  EXPECT_FLOAT_EQ(out.pair_primal.at(0, 0, 0), float(0 + right + 100 + left));
  // x = 1: both; x = 2: only its left neighbour.
  EXPECT_FLOAT_EQ(out.pair_primal.at(1, 0, 0), float(((10 + left) + (0 + right) + (10 + right) + (200 + left)) / 2.0));
  EXPECT_FLOAT_EQ(out.pair_primal.at(2, 0, 0), float(20 + left + 100 + right));
  EXPECT_FLOAT_EQ(out.primal.at(1, 0, 0), 1.0f);  // the plain primal stays as it was
  EXPECT_TRUE(GradientFilm(3, 1).resolve(1).pair_primal.empty());  // off: not allocated
}

// Stage 1's memory accounting: the sums a film holds, the temporal ones only
// with a temporal target, and none after resolve() (docs/tgpt.md "Memory").
TEST(GradientFilmTest, HoldsOnlyTheSumsItNeedsAndReleasesThemOnResolve) {
  const size_t plain = GradientFilm::bytes_per_pixel(false, false);
  EXPECT_LE(plain, 272u);  // 33 doubles and two counts; was 328 with the temporal sums inside
  EXPECT_GT(GradientFilm::bytes_per_pixel(true, false), plain);
  GradientFilm film(16, 8);
  EXPECT_EQ(film.bytes(), 16u * 8u * plain);
  GradientFilm temporal(16, 8, /* temporal = */ true);
  EXPECT_EQ(temporal.bytes(), 16u * 8u * GradientFilm::bytes_per_pixel(true, false));
  film.resolve(1);
  temporal.resolve(1);
  EXPECT_EQ(film.bytes(), 0u);
  EXPECT_EQ(temporal.bytes(), 0u);
}

// resolve() frees the bands of rows as it goes: dy across the border of two
// bands still pairs the rows on either side.
TEST(GradientFilmTest, ResolvesAcrossBandsOfRows) {
  const int w = 4096;  // rows of 1.1 MB: bands of 31 rows at kBandBytes = 32 MiB
  const int band_rows = int((GradientFilm::kBandBytes + w * GradientFilm::bytes_per_pixel(false, false) - 1) /
                            (w * GradientFilm::bytes_per_pixel(false, false)));
  const int h = 2 * band_rows + 1;
  GradientFilm film(w, h);
  GradientSample down, up;
  down.gradient[size_t(OffsetDir::kDown)] = Rgb(0.25f);
  up.gradient[size_t(OffsetDir::kUp)] = Rgb(0.5f);
  up.primal = Rgb(2.0f);
  for (int y : {band_rows - 1, 2 * band_rows - 1}) {
    film.add(7, y, 0, down);
    film.add(7, y + 1, 0, up);
  }
  GradientFilmBuffers out = film.resolve(1);
  for (int y : {band_rows - 1, 2 * band_rows - 1}) {
    EXPECT_FLOAT_EQ(out.dy.at(7, y, 0), 0.75f) << "row " << y;
    EXPECT_FLOAT_EQ(out.primal.at(7, y + 1, 1), 2.0f) << "row " << y + 1;
  }
  EXPECT_FLOAT_EQ(out.dy.at(7, h - 1, 0), 0.0f);  // no constraint beyond the last row
  EXPECT_EQ(out.dy.width(), w);
  EXPECT_EQ(out.dy.height(), h);
  EXPECT_EQ(film.bytes(), 0u);
}

}  // namespace
}  // namespace gdvr
