// Template part of core/recon/temporal_targets.h.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>
#include <vector>

namespace gdvr {

template <typename Scale>
void apply_temporal_targets(const Grid& g, const TemporalTargets& targets, const float* x, Scale&& scale, float* h) {
  const size_t fs = g.frame_size(), last_frame = g.frames > 0 ? size_t(g.frames - 1) * fs : 0;
  // The last frame has no constraints towards a next frame.
  std::fill(h + kTemporalTerms * last_frame, h + kTemporalTerms * g.size(), 0.0f);
  const int64_t W = g.width, last = int64_t(g.size()) - 1;
  const int32_t* offset = targets.next_offset.data();
  // Branch free: a pixel without a target reads itself, and the target's
  // right / lower neighbour is clamped into the grid; its weight is 0 there,
  // and every value of x is finite.
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, int64_t(last_frame) / W, std::max<int64_t>(1, 16384 / W)),
                    [&](const tbb::blocked_range<int64_t>& rows) {
    for (int64_t row = rows.begin(); row != rows.end(); ++row)
      for (int64_t i = row * W; i != (row + 1) * W; ++i) {
        const int32_t o = offset[i];
        const int64_t j = o == TemporalTargets::kNone ? i : i + int64_t(fs) + o;
        const int64_t jx = std::min(j + 1, last), jy = std::min(j + W, last);
        const float xi = x[i], xj = x[j];
        float* out = h + kTemporalTerms * i;
        out[0] = scale(term_index(Term::kDt), size_t(i)) * (xj - xi);
        out[1] = scale(term_index(Term::kDxdt), size_t(i)) * ((x[jx] - xj) - (x[i + 1] - xi));
        out[2] = scale(term_index(Term::kDydt), size_t(i)) * ((x[jy] - xj) - (x[i + W] - xi));
      }
  });
}

}  // namespace gdvr
