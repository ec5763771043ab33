#include "core/recon/temporal_targets.h"

#include "core/recon/gradient_window.h"

namespace gdvr {

TemporalTargets build_temporal_targets(const GradientWindow& window) {
  const Grid g{window.width(), window.height(), window.size()};
  const int W = g.width, H = g.height;
  bool moves = false;
  for (int t = 0; t + 1 < g.frames && !moves; ++t)
    for (float v : window.frames[size_t(t)]->temporal_target.data())
      if (v != 0.0f) {
        moves = true;
        break;
      }
  if (!moves) return {};
  TemporalTargets out;
  out.next_offset.assign(g.size(), TemporalTargets::kNone);
  out.prev_source.assign(g.size(), -1);
  tbb::parallel_for(0, std::max(0, g.frames - 1), [&](int t) {
    const GradientFrame& frame = *window.frames[size_t(t)];
    const Image& target = frame.temporal_target;
    // A pixel whose temporal constraints are all masked claims no target, so
    // that it cannot take one from a source whose constraints hold.
    const auto masked_out = [&](size_t p) {
      bool any = false;
      for (Term term : {Term::kDt, Term::kDxdt, Term::kDydt}) {
        if (!frame.has(term)) continue;
        if (frame.mask(term).empty() || frame.mask(term)[p]) return false;
        any = true;
      }
      return any;
    };
    const size_t base = size_t(t) * g.frame_size(), next = base + g.frame_size();
    std::vector<uint8_t> claimed(g.frame_size(), 0);
    // Scan order decides which of two sources keeps a shared target.
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const int tx = target.empty() ? x : x + int(target.at(x, y, 0));
        const int ty = target.empty() ? y : y + int(target.at(x, y, 1));
        const size_t p = size_t(y) * W + x;
        if (tx < 0 || ty < 0 || tx >= W || ty >= H || claimed[size_t(ty) * W + tx] || masked_out(p)) continue;
        const size_t q = size_t(ty) * W + tx;
        claimed[q] = 1;
        out.next_offset[base + p] = int32_t(int64_t(q) - int64_t(p));
        out.prev_source[next + q] = int32_t(base + p);
      }
  });
  return out;
}

void temporal_targets_adjoint(const Grid& g, const TemporalTargets& targets, const TemporalTermValues& h,
                              bool absolute, bool accumulate, float* out) {
  const size_t W = size_t(g.width), fs = g.frame_size();
  const float plus = 1.0f, minus = absolute ? 1.0f : -1.0f;
  const int32_t* prev = targets.prev_source.data();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, g.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const size_t x = i % W, y = (i / W) % size_t(g.height);
      const bool has_prev_frame = i >= fs;
      // Pixel i as a source: x_t(i) has coefficient −1 in dt, +1 in dxdt and
      // dydt, and −1 in the dxdt / dydt of its left / upper neighbour.
      float v = minus * h.dt[i] + plus * h.dxdt[i] + plus * h.dydt[i];
      if (x > 0) v += minus * h.dxdt[i - 1];
      if (y > 0) v += minus * h.dydt[i - W];
      // Pixel i as a target j of the source k = prev[i]: +1 in dt, −1 in dxdt
      // and dydt; as j + e_x (j + e_y) of the source landing left of (above) it: +1.
      if (has_prev_frame) {
        if (const int32_t k = prev[i]; k >= 0) v += plus * h.dt[k] + minus * h.dxdt[k] + minus * h.dydt[k];
        if (x > 0)
          if (const int32_t k = prev[i - 1]; k >= 0) v += plus * h.dxdt[k];
        if (y > 0)
          if (const int32_t k = prev[i - W]; k >= 0) v += plus * h.dydt[k];
      }
      out[i] = accumulate ? out[i] + v : v;
    }
  });
}

}  // namespace gdvr
