// The bias check of the temporal gradient tests: the mean of an estimate over
// seeds against a converged reference, as z-scores over many pixels.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace gdvr::test {

struct SeedMeanZ {
  double z2 = 0, sum_d = 0, sum_v = 0;
  double sum_seed_var = 0;  // one seed's variance, summed over every value added
  int count = 0;

  // `sum`, `sum_sq` of one value over `seeds` seeds, against `expected` with
  // variance `expected_var`. A value with no variance must equal it exactly.
  void add(double sum, double sum_sq, int seeds, double expected, double expected_var) {
    const double mean = sum / seeds;
    const double var = std::max(0.0, (sum_sq - seeds * mean * mean) / (seeds - 1)) / seeds;
    const double d = mean - expected, v = var + expected_var;
    sum_seed_var += var * seeds;
    if (!(v > 1e-12)) {
      EXPECT_NEAR(d, 0.0, 1e-4);
      return;
    }
    z2 += d * d / v;
    sum_d += d;
    sum_v += v;
    ++count;
  }
  double mean_z2() const { return z2 / std::max(1, count); }
  double aggregate_z() const { return sum_v > 0 ? sum_d / std::sqrt(sum_v) : 0; }
};

}  // namespace gdvr::test
