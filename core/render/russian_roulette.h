// Russian roulette survival probability, shared by every integrator so that
// PT, G-PT and T-GPT terminate paths the same way.
//
// Survival is min(1, max(throughput) * eta^2), applied from rr_depth on.
// Mitsuba 3 caps it at 0.95; gdvr does not (pbrt-v4's rule). With the cap,
// a path whose throughput stays near 1 (a closed room of albedo 0.99) gains
// a factor 0.99 / 0.95 per bounce, the estimator's second moment grows as
// 1.03^depth, and at max_depth 1000 the mean of any affordable sample count
// falls 18 % short of the answer (issue 6, docs/stability.md). Without the
// cap the throughput after the division stays at most 1, so every sample is
// bounded by the path's emitted radiance times its length. The expectation is
// the same under both rules; ordinary scenes (throughput well below 0.95 after
// a few bounces) see no difference in cost.
#pragma once

#include <algorithm>

namespace gdvr {

inline float russian_roulette_survival(float throughput_max, float eta) {
  return std::min(throughput_max * eta * eta, 1.0f);
}

}  // namespace gdvr
