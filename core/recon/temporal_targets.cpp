#include "core/recon/temporal_targets.h"

#include "core/recon/gradient_window.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <climits>
#include <functional>

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
  // The map and the kernels index the grid with 32 bits; a window that large
  // (beyond any tile the tiled solve makes) keeps same-pixel constraints.
  if (!moves || g.size() > size_t(INT32_MAX)) return {};
  TemporalTargets out;
  // One pass over the window's sources; with `only_same_pixel` a source whose
  // offset is not zero gets no target (and takes none from another source).
  const auto claim = [&](bool only_same_pixel) {
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
          if (only_same_pixel && (tx != x || ty != y)) continue;
          const size_t q = size_t(ty) * W + tx;
          claimed[q] = 1;
          out.next_offset[base + p] = int32_t(int64_t(q) - int64_t(p));
          out.prev_source[next + q] = int32_t(base + p);
        }
    });
  };
  claim(/*only_same_pixel=*/false);
  size_t lands = 0, moving = 0;
  for (size_t i = 0; i < out.next_offset.size(); ++i)
    if (out.lands(i)) {
      ++lands;
      moving += out.next_offset[i] != 0;
    }
  if (double(moving) < kMinMovingShare * double(lands)) {
    // Again without the moving sources, so that a pixel whose target one of
    // them took gets its own back.
    claim(/*only_same_pixel=*/true);
    out.all_same_pixel = true;
  }
  return out;
}

TemporalTargetBlocks classify_target_blocks(const Grid& g, const TemporalTargets& targets) {
  TemporalTargetBlocks out;
  out.per_line = target_blocks_per_line(g.width);
  const size_t blocks = size_t(g.rows()) * size_t(out.per_line);
  out.next.assign(blocks, kScatteredBlock);
  out.source.assign(blocks, kScatteredBlock);
  if (targets.next_offset.empty()) return out;
  const int64_t W = g.width, fs = int64_t(g.frame_size()), size = int64_t(g.size());
  const int32_t* next = targets.next_offset.data();
  const int32_t* prev = targets.prev_source.data();
  tbb::parallel_for(0, g.rows(), [&](int row) {
    const bool forward = row / g.height < g.frames - 1, up = row % g.height != 0;
    const int64_t n0 = int64_t(row) * W;
    for (int b = 0; b < out.per_line; ++b) {
      const int64_t c0 = 1 + int64_t(b) * kTargetBlock, c1 = std::min<int64_t>(W, c0 + kTargetBlock);
      const size_t at = size_t(row) * size_t(out.per_line) + size_t(b);
      if (forward) {
        // Pixels without a target read the shared one's neighbourhood and keep 0.
        int64_t o = 0;
        bool found = false, shared = true;
        for (int64_t c = c0; c < c1; ++c) {
          const int32_t oc = next[n0 + c];
          if (oc == TemporalTargets::kNone) continue;
          shared &= !found || oc == o;
          o = oc;
          found = true;
        }
        // Reads x[j], x[j + 1], x[j + W] for j = n + frame_size + o.
        if (shared && n0 + c0 + fs + o >= 0 && n0 + c1 - 1 + fs + o + W <= size - 1) out.next[at] = int32_t(o);
      }
      int64_t d = 0;
      bool found = false, shared = true;
      const auto see = [&](int64_t m) {
        if (prev[m] < 0) return;
        shared &= !found || m - prev[m] == d;
        d = m - prev[m];
        found = true;
      };
      for (int64_t c = c0; c < c1; ++c) {
        see(n0 + c);
        see(n0 + c - 1);
        if (up) see(n0 + c - W);
      }
      // Reads h at n − d, n − 1 − d and (up) n − W − d.
      const int64_t lowest = n0 + c0 - (up ? W : 1) - d, highest = n0 + c1 - 1 - d;
      if (shared && lowest >= 0 && highest < size && d > INT32_MIN && d <= INT32_MAX) out.source[at] = int32_t(d);
    }
  });
  return out;
}

void apply_temporal_targets(const Grid& g, const TemporalTargets& targets, const TemporalTargetBlocks& blocks,
                            const float* x, const TemporalWeights& w, float* const h[kTemporalTerms]) {
  const size_t fs = g.frame_size(), last_frame = g.frames > 0 ? size_t(g.frames - 1) * fs : 0;
  // The last frame has no constraints towards a next frame.
  for (int k = 0; k < kTemporalTerms; ++k) std::fill(h[k] + last_frame, h[k] + g.size(), 0.0f);
  const PoissonKernels& kernels = poisson_kernels();
  const int64_t W = g.width;
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, int64_t(last_frame) / W, std::max<int64_t>(1, 16384 / W)),
                    [&](const tbb::blocked_range<int64_t>& rows) {
    TemporalForwardLine l;
    l.x = x;
    l.width = g.width;
    l.frame_size = int64_t(fs);
    l.last = int64_t(g.size()) - 1;
    l.masked = w.bits != nullptr;
    for (int k = 0; k < kTemporalTerms; ++k) l.term_weight[k] = w.term_weight[k];
    for (int64_t row = rows.begin(); row != rows.end(); ++row) {
      l.begin = row * W;
      l.next_offset = targets.next_offset.data() + l.begin;
      l.block_offset = blocks.next.data() + row * blocks.per_line;
      if (l.masked) l.bits = w.bits + l.begin;
      for (int k = 0; k < kTemporalTerms; ++k) {
        if (!l.masked) l.weight[k] = w.weight[k] + l.begin;
        l.h[k] = h[k] + l.begin;
      }
      kernels.temporal_forward_line(l);
    }
  });
}

double temporal_targets_adjoint(const Grid& g, const TemporalTargets& targets, const TemporalTargetBlocks& blocks,
                                const float* const h[kTemporalTerms], bool absolute, float* out,
                                const float* dot_with) {
  const int64_t W = g.width, H = g.height;
  const PoissonKernels& kernels = poisson_kernels();
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<int64_t>(0, int64_t(g.rows()), std::max<int64_t>(1, 16384 / W)), 0.0,
      [&](const tbb::blocked_range<int64_t>& rows, double acc) {
        std::vector<float> v(static_cast<size_t>(W));
        TemporalAdjointLine l;
        for (int k = 0; k < kTemporalTerms; ++k) l.h[k] = h[k];
        l.width = g.width;
        l.prev_source = targets.prev_source.data();
        l.minus = absolute ? 1.0f : -1.0f;
        l.v = v.data();
        for (int64_t row = rows.begin(); row != rows.end(); ++row) {
          l.begin = row * W;
          l.up = row % H != 0;
          l.block_source = blocks.source.data() + row * blocks.per_line;
          l.out = out + l.begin;
          l.dot_with = dot_with ? dot_with + l.begin : nullptr;
          acc += kernels.temporal_adjoint_line(l);
        }
        return acc;
      },
      std::plus<double>());
}

}  // namespace gdvr
