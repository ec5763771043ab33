// Which constraints of a window exist, per term and pixel, independent of the
// colour channel. A constraint is dropped when it reaches outside the image or
// window (docs/reconstruction.md, "Conventions"), when the caller's mask drops
// it (failed motion vectors, docs/tgpt.md), or when its value or variance is
// NaN/Inf (or the variance is negative) in any channel: one bad sample must
// never poison the solve.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/image/pixel_rect.h"
#include "core/recon/grid.h"
#include "core/recon/gradient_window.h"
#include "core/recon/temporal_targets.h"

namespace gdvr {

struct ConstraintLayout {
  Grid grid;
  int channels = 0;
  // Planar (Grid::index) 0/1 per term; empty when the term has no buffer.
  std::array<std::vector<uint8_t>, kTermCount> valid;
  // Counts of constraints dropped because of non-finite data / caller masks.
  std::array<int64_t, kTermCount> non_finite{};
  std::array<int64_t, kTermCount> masked{};
  bool temporal = false;  // any temporal constraint survives
  // Where the temporal constraints land in the next frame; empty: the same
  // pixel (GradientFrame::temporal_target). A constraint whose target does not
  // exist is dropped and counted in `masked`.
  TemporalTargets targets;

  bool present(Term t) const { return !valid[term_index(t)].empty(); }
  const std::vector<uint8_t>& mask(Term t) const { return valid[term_index(t)]; }
  int64_t total_non_finite() const;
  std::string to_string() const;
};

// Requires window.validate() to have passed. `counted`, when given, limits the
// non_finite / masked counts to constraints at its pixels (a tile's core: the
// halos of neighbouring tiles overlap, and must not count a pixel twice).
ConstraintLayout build_constraint_layout(const GradientWindow& window, const PixelRect* counted = nullptr);

// One byte per pixel (planar), bit term_index(t) set where constraint t exists:
// the L2 solver's whole weight state (PoissonSystem's mask mode).
std::vector<uint8_t> pack_valid_bits(const ConstraintLayout& layout);

// Channel `c` of term `t` in planar layout, 0 where the constraint is invalid
// (so every value the solvers read is finite).
Field gather_term(const GradientWindow& window, const ConstraintLayout& layout, Term t, int c);
// Same into *out (resized), reusing its memory: a 720p window channel is 74 MB,
// and fresh allocations cost page faults on every solve.
void gather_term(const GradientWindow& window, const ConstraintLayout& layout, Term t, int c, Field* out);
// Same for the variances; empty if the term has no variance buffer.
Field gather_variance(const GradientWindow& window, const ConstraintLayout& layout, Term t, int c);
// The frames' data weights (GradientFrame::data_weight) in planar layout, 1
// for a frame without one; empty when no frame of the window has one.
Field gather_data_weight(const GradientWindow& window, const ConstraintLayout& layout);

}  // namespace gdvr
