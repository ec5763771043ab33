// Template part of core/recon/temporal_targets.h.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace gdvr {

template <typename Scale>
void apply_temporal_targets(const Grid& g, const TemporalTargets& targets, const float* x, Scale&& scale,
                            float* h_dt, float* h_dxdt, float* h_dydt) {
  const size_t last_frame = g.frames > 0 ? size_t(g.frames - 1) * g.frame_size() : 0;
  // The last frame has no constraints towards a next frame.
  std::fill(h_dt + last_frame, h_dt + g.size(), 0.0f);
  std::fill(h_dxdt + last_frame, h_dxdt + g.size(), 0.0f);
  std::fill(h_dydt + last_frame, h_dydt + g.size(), 0.0f);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, last_frame, 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const float w_dt = scale(term_index(Term::kDt), i);
      const float w_dxdt = scale(term_index(Term::kDxdt), i);
      const float w_dydt = scale(term_index(Term::kDydt), i);
      h_dt[i] = w_dt != 0.0f ? w_dt * temporal_target_difference(g, targets, Term::kDt, x, i) : 0.0f;
      h_dxdt[i] = w_dxdt != 0.0f ? w_dxdt * temporal_target_difference(g, targets, Term::kDxdt, x, i) : 0.0f;
      h_dydt[i] = w_dydt != 0.0f ? w_dydt * temporal_target_difference(g, targets, Term::kDydt, x, i) : 0.0f;
    }
  });
}

}  // namespace gdvr
