// Jacobi-preconditioned conjugate gradients on a PoissonSystem, hand-written
// over float arrays so that the vector updates are fused into two parallel
// passes per iteration and the dot products are reduced in double
// (deterministically, so results do not depend on the thread count).
#pragma once

#include "core/recon/poisson_operator.h"

namespace gdvr {

struct PcgResult {
  int iterations = 0;
  double relative_residual = 0;  // ‖b − Ax‖ / ‖b‖ at exit
  bool converged = false;
};

// Solves A x = b starting from *x (the warm start). inv_diag = 1 / diag(A).
PcgResult solve_pcg(const PoissonSystem& A, const Field& b, const Field& inv_diag, Field* x, int max_iterations,
                    double tolerance);

}  // namespace gdvr
