// Alias tables (Walker 1977, Vose 1991): O(1) sampling of a discrete
// distribution with a single memory access. The environment map's
// distribution samples through them: its 512 x 256 rows do not fit in L2, and
// the cutpoint search of Distribution1D costs two dependent cache misses per
// row (the cutpoint, then the cdf), which profiles showed as most of an
// environment sample's time.
//
// Unlike inversion (Distribution1D), the map from u to a bin is not monotonic;
// gdvr's samplers are independent, so nothing relies on it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace gdvr {

// One slot: bin `index` keeps the fraction q of the slot, `alias` the rest.
// Both pmfs sit in the slot so that a sample reads nothing else.
struct AliasSlot {
  float q = 0;
  uint32_t alias = 0;
  float pmf = 0;        // pmf of the slot's own bin
  float alias_pmf = 0;  // pmf of bin `alias`
};

struct AliasSample {
  size_t index = 0;
  float pmf = 0;
  float u_remapped = 0;  // uniform in [0, 1) within the selected bin
};

// Samples from n slots starting at `slots`.
AliasSample sample_alias(const AliasSlot* slots, size_t n, float u);

// Appends the n slots of `weights` (non-negative; non-finite counts as zero)
// to `slots`; returns the total weight (0: all slots get pmf 0 and are never
// selected by a marginal that gives this table zero weight).
double build_alias_table(const float* weights, size_t n, std::vector<AliasSlot>* slots);

}  // namespace gdvr
