#include "core/recon/temporal_targets.h"

#include "core/recon/gradient_window.h"

#include <tbb/parallel_reduce.h>

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
  if (!moves) return {};
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

namespace {

// One line of the adjoint into v[0, W): pixel i = begin + x. `up` says whether
// the line above is in the same frame. Plain pointers, so that the loop keeps
// nothing in memory that a store could alias.
void adjoint_line(const float* __restrict h, const int32_t* __restrict prev, int64_t begin, int64_t W, bool up,
                  float minus, float* __restrict v) {
  constexpr int kT = kTemporalTerms;
  static const float kZeros[kT] = {0, 0, 0};
  for (int64_t x = 0; x < W; ++x) {
    const int64_t i = begin + x;
    const float* own = h + kT * i;
    const float* left = x > 0 ? own - kT : kZeros;
    const float* above = up ? own - kT * W : kZeros;
    // Pixel i as a source: x_t(i) has coefficient −1 in dt, +1 in dxdt and
    // dydt, and −1 in the dxdt / dydt of its left / upper neighbour.
    float s = minus * own[0] + own[1] + own[2] + minus * (left[1] + above[2]);
    // Pixel i as the target j of the source prev[i]: +1 in dt, −1 in dxdt
    // and dydt; as j + e_x (j + e_y) of the source landing left of (above)
    // it: +1. prev is −1 throughout the window's first frame.
    const int32_t k = prev[i];
    const int32_t kl = x > 0 ? prev[i - 1] : -1;
    const int32_t ku = up ? prev[i - W] : -1;
    const float* src = k >= 0 ? h + kT * int64_t(k) : kZeros;
    const float* src_left = kl >= 0 ? h + kT * int64_t(kl) : kZeros;
    const float* src_above = ku >= 0 ? h + kT * int64_t(ku) : kZeros;
    s += src[0] + minus * (src[1] + src[2]) + src_left[1] + src_above[2];
    v[x] = s;
  }
}

}  // namespace

double temporal_targets_adjoint(const Grid& g, const TemporalTargets& targets, const float* h, bool absolute,
                                float* out, const float* dot_with) {
  const int64_t W = g.width, H = g.height;
  const float minus = absolute ? 1.0f : -1.0f;
  const int32_t* prev = targets.prev_source.data();
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<int64_t>(0, int64_t(g.rows()), std::max<int64_t>(1, 16384 / W)), 0.0,
      [&](const tbb::blocked_range<int64_t>& rows, double acc) {
        std::vector<float> v(static_cast<size_t>(W));
        for (int64_t row = rows.begin(); row != rows.end(); ++row) {
          adjoint_line(h, prev, row * W, W, row % H != 0, minus, v.data());
          float* __restrict o = out + row * W;
          for (int64_t x = 0; x < W; ++x) o[x] += v[size_t(x)];
          if (!dot_with) continue;
          // Eight partial sums, as the CG kernels keep (poisson_kernels.h).
          const float* __restrict p = dot_with + row * W;
          float part[8] = {};
          int64_t x = 0;
          for (; x + 8 <= W; x += 8)
            for (int l = 0; l < 8; ++l) part[l] += p[x + l] * v[size_t(x + l)];
          for (; x < W; ++x) part[x % 8] += p[x] * v[size_t(x)];
          acc += ((part[0] + part[1]) + (part[2] + part[3])) + ((part[4] + part[5]) + (part[6] + part[7]));
        }
        return acc;
      },
      std::plus<double>());
}

}  // namespace gdvr
