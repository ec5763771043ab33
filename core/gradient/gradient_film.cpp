#include "core/gradient/gradient_film.h"

#include <algorithm>

namespace gdvr {
namespace {

// The variance of the mean of `spp` samples from the two independent half
// means A (even sample indices, n_a samples, sum sum_a) and B (the rest):
// E[(A - B)^2] = s^2 (1/n_a + 1/n_b), Var(mean) = s^2 / n.
struct HalfVariance {
  double n, n_a, n_b;
  explicit HalfVariance(int spp) : n(std::max(1, spp)), n_a((spp + 1) / 2), n_b(spp / 2) {}
  double operator()(double sum, double sum_a) const {
    if (n_b < 1) return 0.0;
    const double a = sum_a / n_a, b = (sum - sum_a) / n_b;
    return (a - b) * (a - b) / (1.0 / n_a + 1.0 / n_b) / n;
  }
};

}  // namespace

void GradientFilm::add(int x, int y, uint32_t sample_index, const GradientSample& s) {
  Sums& p = pixels_[size_t(y) * width_ + x];
  const bool half_a = (sample_index & 1u) == 0;
  for (int c = 0; c < 3; ++c) {
    p.primal[c] += s.primal[c];
    p.direct[c] += s.direct[c];
    if (half_a) p.primal_a[c] += s.primal[c];
    for (int o = 0; o < kOffsetCount; ++o) {
      p.grad[o][c] += s.gradient[size_t(o)][c];
      if (half_a) p.grad_a[o][c] += s.gradient[size_t(o)][c];
    }
  }
  p.shifts += uint32_t(s.shifts);
  p.failures += uint32_t(s.failures);
  if (!pairs_.empty()) {
    PairSums& q = pairs_[size_t(y) * width_ + x];
    for (int o = 0; o < kOffsetCount; ++o) {
      const int nx = x + kOffsetDx[size_t(o)], ny = y + kOffsetDy[size_t(o)];
      if (nx < 0 || ny < 0 || nx >= width_ || ny >= height_) continue;
      for (int c = 0; c < 3; ++c) {
        q.base[c] += s.pair_base[size_t(o)][c];
        q.into[o][c] += s.pair_offset[size_t(o)][c];
        if (half_a) {
          q.base_a[c] += s.pair_base[size_t(o)][c];
          q.into_a[o][c] += s.pair_offset[size_t(o)][c];
        }
      }
    }
  }
  if (temporal_) {
    for (int c = 0; c < 3; ++c) {
      p.temporal[c] += s.temporal[c];
      if (half_a) p.temporal_a[c] += s.temporal[c];
    }
    p.temporal_failures += s.temporal_failed ? 1u : 0u;
  }
}

GradientFilmBuffers GradientFilm::resolve(int spp) const {
  const int w = width_, h = height_;
  GradientFilmBuffers b;
  b.primal = Image(w, h, 3);
  b.dx = Image(w, h, 3);
  b.dy = Image(w, h, 3);
  b.direct = Image(w, h, 3);
  b.primal_var = Image(w, h, 3);
  b.dx_var = Image(w, h, 3);
  b.dy_var = Image(w, h, 3);
  b.shift_failure_rate = Image(w, h, 1);
  if (temporal_) {
    b.temporal = Image(w, h, 3);
    b.temporal_var = Image(w, h, 3);
    b.temporal_failure_rate = Image(w, h, 1);
  }
  const HalfVariance variance(spp);
  const double n = variance.n;
  auto at = [&](int x, int y) -> const Sums& { return pixels_[size_t(y) * w + x]; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Sums& p = at(x, y);
      for (int c = 0; c < 3; ++c) {
        b.primal.at(x, y, c) = float(p.primal[c] / n);
        b.direct.at(x, y, c) = float(p.direct[c] / n);
        b.primal_var.at(x, y, c) = float(variance(p.primal[c], p.primal_a[c]));
        if (x + 1 < w) {
          const Sums& q = at(x + 1, y);
          double sum = p.grad[int(OffsetDir::kRight)][c] + q.grad[int(OffsetDir::kLeft)][c];
          double sum_a = p.grad_a[int(OffsetDir::kRight)][c] + q.grad_a[int(OffsetDir::kLeft)][c];
          b.dx.at(x, y, c) = float(sum / n);
          b.dx_var.at(x, y, c) = float(variance(sum, sum_a));
        }
        if (y + 1 < h) {
          const Sums& q = at(x, y + 1);
          double sum = p.grad[int(OffsetDir::kDown)][c] + q.grad[int(OffsetDir::kUp)][c];
          double sum_a = p.grad_a[int(OffsetDir::kDown)][c] + q.grad_a[int(OffsetDir::kUp)][c];
          b.dy.at(x, y, c) = float(sum / n);
          b.dy_var.at(x, y, c) = float(variance(sum, sum_a));
        }
      }
      b.shift_failure_rate.at(x, y, 0) = p.shifts > 0 ? float(double(p.failures) / p.shifts) : 0.0f;
      if (temporal_) {
        for (int c = 0; c < 3; ++c) {
          b.temporal.at(x, y, c) = float(p.temporal[c] / n);
          b.temporal_var.at(x, y, c) = float(variance(p.temporal[c], p.temporal_a[c]));
        }
        b.temporal_failure_rate.at(x, y, 0) = float(double(p.temporal_failures) / n);
      }
    }
  if (!pairs_.empty()) resolve_pair_primal(spp, &b);
  return b;
}

// I(p) from each neighbour j's pair: p's weighted estimates for that pair
// plus j's offsets into p; the mean over the existing neighbours. A pixel
// without neighbours (a 1x1 image) keeps the plain primal.
void GradientFilm::resolve_pair_primal(int spp, GradientFilmBuffers* b) const {
  const int w = width_, h = height_;
  b->pair_primal = b->primal;
  b->pair_primal_var = b->primal_var;
  const HalfVariance variance(spp);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const PairSums& p = pairs_[size_t(y) * w + x];
      double sum[3], sum_a[3];
      int neighbours = 0;
      for (int c = 0; c < 3; ++c) sum[c] = p.base[c], sum_a[c] = p.base_a[c];
      for (int o = 0; o < kOffsetCount; ++o) {
        const int nx = x + kOffsetDx[size_t(o)], ny = y + kOffsetDy[size_t(o)];
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        ++neighbours;
        const int back = o ^ 1;  // right <-> left, down <-> up: the neighbour's offset towards p
        const PairSums& q = pairs_[size_t(ny) * w + nx];
        for (int c = 0; c < 3; ++c) sum[c] += q.into[back][c], sum_a[c] += q.into_a[back][c];
      }
      if (neighbours == 0) continue;
      for (int c = 0; c < 3; ++c) {
        // The mean over neighbours of per-sample sums: divide sums by their count.
        b->pair_primal.at(x, y, c) = float(sum[c] / (variance.n * neighbours));
        b->pair_primal_var.at(x, y, c) =
            float(variance(sum[c], sum_a[c]) / (double(neighbours) * double(neighbours)));
      }
    }
}

}  // namespace gdvr
