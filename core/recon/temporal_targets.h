// Motion-compensated temporal constraints (Manzi et al. 2016, §4;
// docs/reconstruction.md, "Motion-compensated temporal terms"): the temporal
// terms of pixel p of frame t link it to pixel j(p) = p + o(p) of frame t+1
// instead of to p itself,
//
//   (H_dt x)(p)   = x_{t+1}(j) − x_t(p)
//   (H_dxdt x)(p) = [x_{t+1}(j + e_x) − x_{t+1}(j)] − [x_t(p + e_x) − x_t(p)]
//   (H_dydt x)(p) = [x_{t+1}(j + e_y) − x_{t+1}(j)] − [x_t(p + e_y) − x_t(p)].
//
// The map p → j is one to one (build_temporal_targets drops the later of two
// sources that land on one pixel), so every pixel of frame t+1 is the target of
// at most one constraint: Hᵀ is then a gather (each pixel reads the few
// constraints that touch it), parallel and deterministic like the stencil of
// the same-pixel terms, which core/recon/poisson_operator.cpp keeps for
// windows without motion.
#pragma once

#include <cstdint>
#include <vector>

#include "core/recon/grid.h"
#include "core/recon/poisson_kernels.h"
#include "core/recon/term.h"

namespace gdvr {

struct TemporalTargets {
  // Planar over the window's grid. next_offset[i]: the target of pixel i of
  // frame t is i + frame_size + next_offset[i] (a pixel of frame t+1).
  // prev_source[i]: the pixel of frame t−1 whose constraints land on pixel i,
  // or −1. Empty: every temporal constraint links the same pixel.
  std::vector<int32_t> next_offset;
  std::vector<int32_t> prev_source;

  // Every constraint that kept its target stays on its own pixel (those that
  // moved were dropped: see kMinMovingShare), so the stencil applies them.
  bool all_same_pixel = false;

  // No map, or one the stencil applies: the solvers' same-pixel paths.
  bool empty() const { return next_offset.empty() || all_same_pixel; }
  // next_offset of a pixel without a target (outside the image, another
  // source landed there first, or the window's last frame).
  static constexpr int32_t kNone = kNoTemporalTarget;
  bool lands(size_t i) const { return next_offset[i] != kNone; }
};

struct GradientWindow;
// Below this share of a window's temporal constraints leaving their pixel,
// the few that do are dropped rather than paying the two motion-following
// passes for every pixel (1.14-1.44x the stencil's solve time,
// docs/benchmarks.md): their pixels keep their spatial terms, the rest the
// stencil. Shares measured on the four animations of docs/benchmarks.md: 4 %
// on the demo (a box moving under a slow camera), 31 % stiff, 81 % textured,
// 98 % indirect. Following the demo's 4 % instead read the same within the
// spread of two runs each (docs/benchmarks.md), so the simpler solve stays.
constexpr double kMinMovingShare = 0.1;

// The window's map, from each frame's GradientFrame::temporal_target (frames
// without one link the same pixel; pixels whose temporal terms are all masked
// link nothing); empty when every offset of frames
// 0..W−2 is zero, so windows without motion keep the stencil (and for a grid
// of more than 2³¹ pixels, which 32-bit indices cannot address), and
// all_same_pixel (with the moving constraints left without a target) when
// fewer than kMinMovingShare of them move.
TemporalTargets build_temporal_targets(const GradientWindow& window);

// The per-constraint values of the three temporal terms live in three planes
// over the window's grid (dt, dxdt, dydt; 0 where a term has no constraint).
constexpr int kTemporalTerms = 3;
inline int temporal_slot(Term t) { return term_index(t) - term_index(Term::kDt); }

// Per line of the grid and block of kTargetBlock columns (from column 1,
// core/recon/poisson_kernels.h): the offset all the block's targets share
// (`next`), and the d with prev_source[m] = m − d for every pixel m of the
// block, its left neighbour and (below a frame's first line) its upper
// neighbour that has a source (`source`); kScatteredBlock where they differ or
// a contiguous read would leave the grid. Contiguous blocks are read as
// vectors, scattered ones gathered (docs/benchmarks.md: the motion-following
// solve costs 1.44x (L2) and 1.14x (L1) the same-pixel stencil's on a 2-px
// pan, against 1.9x and 1.53x one pixel at a time).
struct TemporalTargetBlocks {
  int per_line = 0;
  std::vector<int32_t> next, source;  // index: line · per_line + block
};
inline int target_blocks_per_line(int width) { return width > 1 ? (width - 1 + kTargetBlock - 1) / kTargetBlock : 0; }
TemporalTargetBlocks classify_target_blocks(const Grid& g, const TemporalTargets& targets);

// The weights of the temporal terms: `bits` (the packed validity bytes of
// PoissonSystem's mask mode) with a constant weight per term, or, where bits is
// null, per-constraint float weights (planar over the grid).
struct TemporalWeights {
  const uint8_t* bits = nullptr;
  float term_weight[kTemporalTerms] = {};
  const float* weight[kTemporalTerms] = {};
};

// h[slot(term)][i] = w_term(i) · (H_term x)(i) for every pixel of frames
// 0..W−2, and 0 in the last frame. With temporal_targets_adjoint(h) this is
// the temporal part of A x. (Two passes through h measured 1.7x faster than
// one pass that evaluates each constraint where it is needed, on a 128²
// window of 20 frames.)
void apply_temporal_targets(const Grid& g, const TemporalTargets& targets, const TemporalTargetBlocks& blocks,
                            const float* x, const TemporalWeights& w, float* const h[kTemporalTerms]);

// v(i) = Σ over the temporal constraints touching pixel i of c·h(constraint),
// with c the coefficient of x(i) in that constraint (±1), or |c| = 1 when
// `absolute` (the diagonal of Hᵀ W H is the adjoint of the weights with
// absolute coefficients). out(i) += v(i); returns Σ dot_with(i)·v(i) when
// `dot_with` is given (CG's p·Ap), else 0.
double temporal_targets_adjoint(const Grid& g, const TemporalTargets& targets, const TemporalTargetBlocks& blocks,
                                const float* const h[kTemporalTerms], bool absolute, float* out,
                                const float* dot_with = nullptr);

// (H_term x)(i) for one temporal term at pixel i (the constraint must exist).
inline float temporal_target_difference(const Grid& g, const TemporalTargets& targets, Term term, const float* x,
                                        size_t i) {
  const size_t j = size_t(int64_t(i) + int64_t(g.frame_size()) + targets.next_offset[i]);
  const size_t sx = 1, sy = size_t(g.width);
  switch (term) {
    case Term::kDt: return x[j] - x[i];
    case Term::kDxdt: return (x[j + sx] - x[j]) - (x[i + sx] - x[i]);
    case Term::kDydt: return (x[j + sy] - x[j]) - (x[i + sy] - x[i]);
    default: return 0.0f;
  }
}

}  // namespace gdvr

