// The inner loops of the window solve, compiled once per x86-64 instruction
// set (poisson_kernels.inl): one line of the operator's stencil (q = A p on
// line (t, y), PoissonSystem::apply), the two passes of the motion-following
// temporal terms (core/recon/temporal_targets.h) and the two vector passes of
// each CG iteration (solve_pcg). They are most of stage 2's time; the baseline
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

// The motion-following temporal terms (core/recon/temporal_targets.h), one
// line at a time: column 0 alone, then blocks of kTargetBlock columns. A block
// whose targets (sources) sit at one offset from its pixels reads them as
// contiguous vectors; a scattered block gathers them, with the same
// arithmetic per pixel (the two may differ in the sign of a zero). Which
// blocks are contiguous does not depend on the instruction set. Real motion
// fields change their rounded offset every few pixels: blocks of 8 rather
// than 16 halve the share of the textured interior's blocks whose targets
// are scattered (40 % to 20 %) and cost the same on a uniform pan.
constexpr int kTargetBlock = 8;
// A block whose targets or sources do not share one offset.
constexpr int32_t kScatteredBlock = INT32_MIN;
// TemporalTargets::next_offset of a pixel without a target.
constexpr int32_t kNoTemporalTarget = INT32_MIN;

// h_k = w_k · (H_k x) on one line for the three temporal terms k (dt, dxdt,
// dydt), written to three planes.
struct TemporalForwardLine {
  const float* x = nullptr;  // the whole grid
  int64_t begin = 0;         // grid index of the line's column 0
  int width = 0;
  int64_t frame_size = 0;
  int64_t last = 0;                       // the grid's last index
  const int32_t* next_offset = nullptr;   // the line's target offsets
  const int32_t* block_offset = nullptr;  // per block: the offset its landing pixels share, or kScatteredBlock
  // Mask mode: the line's validity bytes (bits 3, 4, 5: dt, dxdt, dydt) and
  // a constant weight per term; float mode: the line's weights per term.
  bool masked = false;
  const uint8_t* bits = nullptr;
  float term_weight[3] = {};
  const float* weight[3] = {};
  float* h[3] = {};  // the line of each plane
};

// v = Hᵀ h on one line, out += v; returns dot_with · v (0 without dot_with).
struct TemporalAdjointLine {
  const float* h[3] = {};  // the whole planes
  int64_t begin = 0;
  int width = 0;
  bool up = false;                        // the line above is in the same frame
  const int32_t* prev_source = nullptr;   // the whole grid's
  const int32_t* block_source = nullptr;  // per block: d with prev_source[m] = m − d wherever one exists, or kScatteredBlock
  float minus = -1.0f;                    // −1, or +1 for the absolute coefficients (the diagonal)
  float* v = nullptr;                     // scratch, width floats
  float* out = nullptr;                   // the line of out
  const float* dot_with = nullptr;        // the line of dot_with, or null
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
  void (*temporal_forward_line)(const TemporalForwardLine& line) = nullptr;
  float (*temporal_adjoint_line)(const TemporalAdjointLine& line) = nullptr;
};

// The fastest variant this CPU runs, or the one the environment variable
// GDVR_POISSON_KERNELS names ("baseline", "avx2", "avx512") where it runs.
const PoissonKernels& poisson_kernels();
// Every variant this CPU runs, baseline first (for tests and benchmarks).
std::vector<const PoissonKernels*> poisson_kernel_variants();

}  // namespace gdvr
