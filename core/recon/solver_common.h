// Internal glue shared by the solvers in core/recon (not a public API).
#pragma once

#include "core/recon/constraint_layout.h"
#include "core/recon/poisson_operator.h"
#include "core/recon/recon_result.h"
#include "core/recon/recon_settings.h"

namespace gdvr {

// Per-method solvers; `result->frames` arrive allocated (zeros) and shaped.
Status solve_screened_poisson_l2(const GradientWindow& window, const ConstraintLayout& layout,
                                 const ReconSettings& settings, ReconResult* result);
Status solve_irls_l1(const GradientWindow& window, const ConstraintLayout& layout, const ReconSettings& settings,
                     ReconResult* result);
Status solve_control_variates(const GradientWindow& window, const ConstraintLayout& layout,
                              const ReconSettings& settings, ReconResult* result);

// The screened Poisson operator of the L2 problem: a constant weight per term
// (α² for the primal, the term weights for the rest) on the layout's masks,
// divided by max(1, α²) so that every float weight stays ≤ 1 for a huge α
// (the minimiser does not change). The L2 solve uses it, and so does the L1
// solve's low-frequency correction.
PoissonSystem screened_poisson_system(const ConstraintLayout& layout, const ReconSettings& settings);

// Copies planar channel c into the result images.
void scatter_channel(const Grid& grid, const Field& x, int c, ReconResult* result);

// A dropped primal still gets this fraction of the primal weight (target 0),
// so a pixel whose constraints are all dropped stays determined and finite.
constexpr float kDroppedPrimalWeight = 1e-6f;

// 1 / d, and 0 where the row of A is empty (d = 0), which leaves that unknown at
// its warm start instead of producing Inf.
void invert_diagonal(Field* d);

}  // namespace gdvr
