// What every shift mapping returns for one base path and one neighbour j, and
// the balance-heuristic weight of a pair (REFERENCE.md §2): for each
// technique t of the base path (emitter sampling at x_k, or BSDF sampling at
// x_k hitting emission at x_{k+1}) the shift gives the offset's contribution
// c_o = f(T x)|J| / p(x) and the ratio r = p(T x)|J| / p(x), accumulated per
// vertex in double; the pair's weight is w = 1 / (1 + r) and the gradient
// sample w (c_o - c_b). A shift failure makes c_o = 0, w = 1 (a finite
// difference), which keeps the estimator unbiased.
#pragma once

#include <cmath>
#include <vector>

#include "core/gradient/path_record.h"

namespace gdvr {

struct ShiftResult {
  Rgb gradient;        // Σ_t w_t (c_o,t - c_b,t): this generation's estimate of I_j - I_i (indirect part)
  Rgb offset_primal;   // Σ_t w_t c_o,t (diagnostic)
  bool failed = false; // some technique's shift failed (counted per pixel)
};

// Test and debugging hook: the ratio of every technique in path order (0 after
// a failure) and the offset path as a record, so the shift can be run backwards.
struct ShiftTrace {
  std::vector<double> ratios;
  PathRecord offset;
};

// w = p(x) / (p(x) + p(T x)|J|) from the ratio r (Kettunen et al. 2015, Eq. 9),
// with the release's epsilon in the denominator. Non-finite r gives w = 0.
inline double pair_mis_weight(double ratio, double epsilon) {
  if (!(ratio >= 0)) return 1.0;  // NaN: treated as a failure
  if (std::isinf(ratio)) return 0.0;
  return 1.0 / (1.0 + ratio + epsilon);
}

}  // namespace gdvr
