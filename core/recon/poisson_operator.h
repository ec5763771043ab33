// The matrix-free normal-equations operator of the (weighted) screened Poisson
// objective (Kettunen et al. 2015, with the temporal terms of Manzi et al.
// 2016; docs/reconstruction.md) over one channel of a window:
//
//   E(x) = Σ_p w_primal(p) (x(p) − g(p))² + Σ_{term} Σ_p w_term(p) ((H_term x)(p) − d_term(p))²
//   A = W_primal + Σ H_termᵀ W_term H_term,   b = W_primal g + Σ H_termᵀ W_term d_term.
//
// The L2 solve uses per-term constant weights (α² for the primal) on a packed
// validity mask (one byte per pixel instead of six float arrays: the window
// solve is memory bound), the L1 IRLS solve per-constraint float weights
// 1/(|r| + ε). A is applied directly on the planar arrays as a 3×3×3 stencil
// (never assembled), in parallel with TBB, by the fastest of the kernels in
// core/recon/poisson_kernels.h this CPU runs.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/recon/grid.h"
#include "core/recon/temporal_targets.h"
#include "core/recon/term.h"

namespace gdvr {

class PoissonSystem {
 public:
  // Per-constraint float weights, all zero; temporal = false ignores dt/dxdt/dydt.
  PoissonSystem(Grid grid, bool temporal);
  // Constant weight per term on a packed mask: bit term_index(t) of valid_bits[i]
  // says whether constraint t exists at pixel i (it must be clear outside the
  // image/window, as for the float weights). A cleared primal bit keeps
  // `dropped_primal_weight` instead of 0.
  PoissonSystem(Grid grid, bool temporal, const std::array<float, kTermCount>& term_weights,
                float dropped_primal_weight, std::vector<uint8_t> valid_bits);

  const Grid& grid() const { return grid_; }
  bool temporal() const { return temporal_; }
  // Per-constraint weights (float mode only), planar; must stay 0 where a
  // constraint does not exist (last column for dx, last row for dy, last frame
  // for temporal terms).
  Field& weights(Term t) { return w_[term_index(t)]; }
  const Field& weights(Term t) const { return w_[term_index(t)]; }

  // q = A p; returns p·q (the CG step needs it, fusing saves a pass).
  double apply(const float* p, float* q) const;
  // b = W_primal g + Σ Hᵀ W d, with targets indexed by term (primal = g). In
  // mask mode the targets must be 0 where a constraint does not exist (as
  // gather_term leaves them): the weights are then applied unconditionally.
  void rhs(const std::array<const Field*, kTermCount>& targets, Field* b) const;
  // diag(A), for the Jacobi preconditioner.
  void diagonal(Field* d) const;

  // The temporal terms link each pixel to its target in the next frame
  // (core/recon/temporal_targets.h) instead of to the same pixel; `targets`
  // (the layout's) must outlive the system. Empty targets keep the stencil.
  void follow_temporal_targets(const TemporalTargets* targets);

  // The rows of grid, split into TBB ranges of about `kChunkPixels` pixels.
  int row_grain() const;

 private:
  void rhs_masked(const std::array<const Field*, kTermCount>& targets, Field* b) const;
  void rhs_stencil(const std::array<const Field*, kTermCount>& targets, Field* b) const;
  bool follows_motion() const { return temporal_targets_ != nullptr; }
  // Whether the 3×3×3 stencil carries the temporal terms (it does unless they follow motion).
  bool stencil_temporal() const { return temporal_ && !follows_motion(); }
  // Adds the motion-following temporal terms' part of A p to q; returns its p·(A p).
  double apply_temporal_targets_part(const float* p, float* q) const;
  // The three planes of temporal_scratch_ (dt, dxdt, dydt).
  std::array<float*, kTemporalTerms> temporal_planes() const;
  // Fills temporal_scratch_ with w · value(term, i) per temporal constraint
  // and adds its adjoint to *out.
  template <typename Value>
  void add_temporal_adjoint(Value&& value, bool absolute, float* out) const;
  // Weight of constraint t at pixel i in either mode (setup passes only).
  float weight_at(Term t, size_t i) const {
    const int k = term_index(t);
    if (!masked_) return w_[k][i];
    const bool on = (bits_[i] >> k) & 1;
    return on ? term_w_[k] : (t == Term::kPrimal ? dropped_primal_w_ : 0.0f);
  }

  Grid grid_;
  bool temporal_;
  bool masked_ = false;
  std::array<Field, kTermCount> w_;        // float mode
  std::array<float, kTermCount> term_w_{};  // mask mode
  float dropped_primal_w_ = 0;
  std::vector<uint8_t> bits_;
  Field zero_row_;                 // stands in for weight rows outside the grid
  std::vector<uint8_t> zero_bits_;  // same for mask rows
  // Per line (t, y) and span of columns: the mask is constant over the columns
  // that span's stencil reads (ConstWeights apply); all ones for outside lines.
  std::vector<uint8_t> uniform_spans_, all_uniform_;
  const TemporalTargets* temporal_targets_ = nullptr;
  TemporalTargetBlocks target_blocks_;
  // Per-constraint values of the motion-following terms (three planes: dt,
  // dxdt, dydt); apply() is called by one CG at a time.
  mutable Field temporal_scratch_;
};

// (H_t x)(p) − d(p) for every valid constraint of term t (0 elsewhere); the
// temporal terms follow `targets` when it is given and not empty.
void constraint_residuals(const Grid& grid, Term t, const float* x, const Field& target,
                          const std::vector<uint8_t>& valid, Field* r, const TemporalTargets* targets = nullptr);

}  // namespace gdvr
