// What a window solve returns: one image per frame of the window plus the
// numbers a caller logs or tests (iterations, residuals, dropped constraints).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/recon/term.h"

namespace gdvr {

struct ReconStats {
  int cg_iterations = 0;            // summed over channels (and IRLS rounds)
  int outer_iterations = 0;         // IRLS rounds or control-variate sweeps, per channel
  double relative_residual = 0;     // worst channel, last linear solve
  std::array<int64_t, kTermCount> non_finite_constraints{};  // dropped for NaN/Inf
  std::array<int64_t, kTermCount> masked_constraints{};      // dropped by caller masks
  int64_t non_finite_outputs = 0;   // should stay 0; replaced by the primal (or 0)
  double seconds = 0;

  int64_t total_non_finite() const {
    int64_t n = 0;
    for (int64_t v : non_finite_constraints) n += v;
    return n;
  }
  std::string to_string() const;
};

struct ReconResult {
  std::vector<Image> frames;  // same order and shape as the window's frames
  ReconStats stats;
};

}  // namespace gdvr
