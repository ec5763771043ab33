// The inner loops of the window solve, compiled once per x86-64 instruction
// set (poisson_kernels.inl): one line of the operator's stencil (q = A p on
// line (t, y), PoissonSystem::apply) and the two vector passes of each CG
// iteration (solve_pcg). They are most of stage 2's time; the baseline
// x86-64 build runs them four floats wide, AVX2 eight and AVX-512 sixteen.
//
// Every variant does each element's arithmetic in the same order and no
// multiply-add is fused (-ffp-contract=off for the whole build), and the dot
// products keep eight explicit partial sums whatever the vector width, so all
// variants give the same bits (PoissonKernelsTest): a farm of mixed CPUs
// renders the same frames.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace gdvr {

// The mask-mode stencil checks for constant weights per span of this many
// columns (PoissonSystem precomputes which spans are uniform).
constexpr int kStencilSpan = 64;

// One line (t, y) of q = A p. Rows outside the grid are clamped by the caller
// (they only ever meet zero weights); weight rows outside it are zero rows.
struct StencilLine {
  // x[dt + 1][dy + 1]: line y + dy of frame t + dt of p.
  const float* x[3][3] = {};
  const float* p = nullptr;  // line (t, y) of p (= x[1][1])
  float* q = nullptr;        // line (t, y) of q
  int width = 0;
  bool temporal = false;

  // Mask mode (masked = true): constant weight per term where its bit is set
  // (bit k of a mask byte: term k of core/recon/term.h). Lines (t, y),
  // (t, y − 1), (t − 1, y), (t − 1, y − 1).
  bool masked = false;
  const uint8_t* mask[4] = {};
  const uint8_t* uniform_spans = nullptr;  // per span: all four mask lines constant over it
  float term_weight[6] = {};
  float dropped_primal_weight = 0;

  // Float mode: per-constraint weight rows, in this order: primal, dx, dy,
  // dy (line y − 1), dt, dt (frame t − 1), dxdt, dxdt (t − 1), dydt,
  // dydt (y − 1), dydt (t − 1), dydt (t − 1, y − 1).
  const float* weight_rows[12] = {};
};

struct PcgSums {
  float first = 0, second = 0;
};

struct PoissonKernels {
  const char* isa = "";  // "x86-64", "avx2", "avx512"
  // q = A p on one line; returns p·q over the line.
  float (*apply_line)(const StencilLine& line) = nullptr;
  // r[i] −= step q[i] over [begin, end); returns (r·r, r·M·r) with M = inv_diag.
  PcgSums (*update_residual)(float* r, const float* q, const float* inv_diag, float step, size_t begin,
                             size_t end) = nullptr;
  // x[i] += step p[i]; then p[i] = M[i] r[i] + beta p[i] unless `last`.
  void (*update_solution)(float* x, float* p, const float* r, const float* inv_diag, float step, float beta,
                          bool last, size_t begin, size_t end) = nullptr;
};

// The fastest variant this CPU runs, or the one the environment variable
// GDVR_POISSON_KERNELS names ("baseline", "avx2", "avx512") where it runs.
const PoissonKernels& poisson_kernels();
// Every variant this CPU runs, baseline first (for tests and benchmarks).
std::vector<const PoissonKernels*> poisson_kernel_variants();

}  // namespace gdvr
