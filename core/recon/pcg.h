// Jacobi-preconditioned conjugate gradients on a PoissonSystem, hand-written
// over float arrays so that the vector updates are fused into two parallel
// passes per iteration (r and the dots; x and p) and the dot products are reduced in double
// (deterministically, so results do not depend on the thread count). The
// passes run on the CPU's fastest kernels (core/recon/poisson_kernels.h).
#pragma once

#include "core/recon/poisson_operator.h"

namespace gdvr {

struct PcgResult {
  int iterations = 0;
  double relative_residual = 0;  // ‖b − Ax‖ / ‖b‖ at exit
  bool converged = false;
};

// The residual, direction and A·direction vectors; reusing one across solves
// (the channels of a window) saves three grid-sized allocations per solve.
struct PcgWorkspace {
  Field r, p, q;
};

// Solves A x = b starting from *x (the warm start). inv_diag = 1 / diag(A).
// `workspace` may be null (then it is allocated here).
PcgResult solve_pcg(const PoissonSystem& A, const Field& b, const Field& inv_diag, Field* x, int max_iterations,
                    double tolerance, PcgWorkspace* workspace = nullptr);

}  // namespace gdvr
