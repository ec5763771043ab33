// What every shift mapping returns for one base path and one neighbour j, and
// the balance-heuristic weight of a pair (Kettunen et al. 2015; docs/gpt.md,
// "Estimators"): for each
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
  Rgb offset_primal;   // Σ_t w_t c_o,t: this generation's share of the neighbour's estimate
  Rgb base_weighted;   // Σ_t w_t c_b,t: its share of the base pixel's own estimate (the pair primal)
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

// The techniques of one generation of a pair, in the base path's order: each
// adds w (c_o − c_b) with w = pair_mis_weight(r); a shift failure from vertex
// i on turns every later technique into a finite difference (c_o = 0, w = 1).
// Shared by the spatial cached shifts and the temporal path-space shift.
class ShiftAccumulator {
 public:
  ShiftAccumulator(const PathRecord& base, double mis_epsilon, std::vector<double>* ratios)
      : base_(base), mis_epsilon_(mis_epsilon), ratios_(ratios) {}

  void technique(Rgb c_b, Rgb c_o, double ratio) {
    if (ratios_) ratios_->push_back(ratio);
    const double w = pair_mis_weight(ratio, mis_epsilon_);
    if (w == 0.0) return;
    Rgb wc_o = w == 1.0 ? Rgb(0.0f) : c_o * float(w);
    if (!is_finite(wc_o)) wc_o = Rgb(0.0f);
    const Rgb wc_b = c_b * float(w);
    result_.offset_primal += wc_o;
    result_.base_weighted += wc_b;
    result_.gradient += wc_o - wc_b;
  }
  // Failure at base vertex i: its later techniques (and its own emitter
  // sampling when `with_nee`) become finite differences.
  void fail_from(size_t i, bool with_nee) {
    result_.failed = true;
    const auto& v = base_.v;
    for (size_t j = i; j < v.size(); ++j) {
      if (j > i) technique(v[j].emission, Rgb(0.0f), 0.0);
      if (v[j].has_nee && (j > i || with_nee)) technique(v[j].nee, Rgb(0.0f), 0.0);
      if (v[j].next == PathNext::kEscaped) technique(v[j].escape, Rgb(0.0f), 0.0);
    }
  }
  const ShiftResult& result() const { return result_; }

 private:
  const PathRecord& base_;
  const double mis_epsilon_;
  std::vector<double>* ratios_;
  ShiftResult result_;
};

}  // namespace gdvr
