#include "core/gradient/gradient_film.h"

#include <algorithm>

namespace gdvr {

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
  const double n = std::max(1, spp);
  const double n_a = (spp + 1) / 2, n_b = spp / 2;
  // Var of the mean from two independent half means A, B (n_a, n_b samples):
  // E[(A - B)^2] = s^2 (1/n_a + 1/n_b), Var(mean) = s^2 / n.
  auto variance = [&](double sum, double sum_a) {
    if (n_b < 1) return 0.0;
    double a = sum_a / n_a, bb = (sum - sum_a) / n_b;
    return (a - bb) * (a - bb) / (1.0 / n_a + 1.0 / n_b) / n;
  };
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
  return b;
}

}  // namespace gdvr
