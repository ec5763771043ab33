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

GradientFilm::GradientFilm(int width, int height, bool temporal, bool pair_primal)
    : width_(width), height_(height), temporal_(temporal) {
  // Bands of at least kBandBytes: glibc serves a request that large with its
  // own mapping and unmaps it on free, so a freed band leaves the resident
  // set at once (a smaller one may stay in the heap, resident).
  const size_t row_bytes = std::max<size_t>(1, size_t(width) * sizeof(Sums));
  band_rows_ = int(std::max<size_t>(1, (kBandBytes + row_bytes - 1) / row_bytes));
  for (int y0 = 0; y0 < height; y0 += band_rows_)
    bands_.emplace_back(size_t(std::min(band_rows_, height - y0)) * size_t(width));
  const size_t n = size_t(width) * size_t(height);
  if (temporal) temporal_sums_.resize(n);
  if (pair_primal) pairs_.resize(n);
}

size_t GradientFilm::bytes() const {
  size_t n = temporal_sums_.capacity() * sizeof(TemporalSums) + pairs_.capacity() * sizeof(PairSums);
  for (const std::vector<Sums>& band : bands_) n += band.capacity() * sizeof(Sums);
  return n;
}

size_t GradientFilm::bytes_per_pixel(bool temporal, bool pair_primal) {
  return sizeof(Sums) + (temporal ? sizeof(TemporalSums) : 0) + (pair_primal ? sizeof(PairSums) : 0);
}

void GradientFilm::add(int x, int y, uint32_t sample_index, const GradientSample& s) {
  Sums& p = sums(x, y);
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
    TemporalSums& t = temporal_sums_[size_t(y) * width_ + x];
    for (int c = 0; c < 3; ++c) {
      t.temporal[c] += s.temporal[c];
      if (half_a) t.temporal_a[c] += s.temporal[c];
    }
    t.failures += s.temporal_failed ? 1u : 0u;
  }
}

// An output layer filled a row at a time: its storage is reserved up front
// and each row is zeroed and written only when resolve() reaches it, so that
// the layers' pages become resident as the film's bands are freed.
class RowGrownLayer {
 public:
  RowGrownLayer(int width, int height, int channels) : width_(width), height_(height), channels_(channels) {
    data_.reserve(size_t(width) * height * channels);
  }
  float* row(int y) {
    const size_t stride = size_t(width_) * channels_;
    data_.resize(size_t(y + 1) * stride, 0.0f);
    return data_.data() + size_t(y) * stride;
  }
  Image take() { return Image(width_, height_, channels_, std::move(data_)); }

 private:
  int width_, height_, channels_;
  std::vector<float> data_;
};

GradientFilmBuffers GradientFilm::resolve(int spp) {
  const int w = width_, h = height_;
  RowGrownLayer primal(w, h, 3), dx(w, h, 3), dy(w, h, 3), direct(w, h, 3), primal_var(w, h, 3), dx_var(w, h, 3),
      dy_var(w, h, 3), failure_rate(w, h, 1);
  const int tc = temporal_ ? 1 : 0;  // the temporal layers: empty without a temporal target
  RowGrownLayer temporal(w * tc, h * tc, 3), temporal_var(w * tc, h * tc, 3), temporal_failure_rate(w * tc, h * tc, 1);
  const HalfVariance variance(spp);
  const double n = variance.n;
  for (int y = 0; y < h; ++y) {
    // Row y reads rows y and y + 1 only: the band before y's is done with.
    if (y % band_rows_ == 0 && y > 0) std::vector<Sums>().swap(bands_[size_t(y / band_rows_ - 1)]);
    float *o_primal = primal.row(y), *o_dx = dx.row(y), *o_dy = dy.row(y), *o_direct = direct.row(y);
    float *o_primal_var = primal_var.row(y), *o_dx_var = dx_var.row(y), *o_dy_var = dy_var.row(y);
    float* o_failure = failure_rate.row(y);
    float *o_temporal = tc ? temporal.row(y) : nullptr, *o_temporal_var = tc ? temporal_var.row(y) : nullptr;
    float* o_temporal_failure = tc ? temporal_failure_rate.row(y) : nullptr;
    for (int x = 0; x < w; ++x) {
      const Sums& p = sums(x, y);
      for (int c = 0; c < 3; ++c) {
        const size_t k = size_t(x) * 3 + size_t(c);
        o_primal[k] = float(p.primal[c] / n);
        o_direct[k] = float(p.direct[c] / n);
        o_primal_var[k] = float(variance(p.primal[c], p.primal_a[c]));
        if (x + 1 < w) {
          const Sums& q = sums(x + 1, y);
          double sum = p.grad[int(OffsetDir::kRight)][c] + q.grad[int(OffsetDir::kLeft)][c];
          double sum_a = p.grad_a[int(OffsetDir::kRight)][c] + q.grad_a[int(OffsetDir::kLeft)][c];
          o_dx[k] = float(sum / n);
          o_dx_var[k] = float(variance(sum, sum_a));
        }
        if (y + 1 < h) {
          const Sums& q = sums(x, y + 1);
          double sum = p.grad[int(OffsetDir::kDown)][c] + q.grad[int(OffsetDir::kUp)][c];
          double sum_a = p.grad_a[int(OffsetDir::kDown)][c] + q.grad_a[int(OffsetDir::kUp)][c];
          o_dy[k] = float(sum / n);
          o_dy_var[k] = float(variance(sum, sum_a));
        }
      }
      o_failure[x] = p.shifts > 0 ? float(double(p.failures) / p.shifts) : 0.0f;
      if (tc) {
        const TemporalSums& t = temporal_sums_[size_t(y) * w + x];
        for (int c = 0; c < 3; ++c) {
          o_temporal[size_t(x) * 3 + size_t(c)] = float(t.temporal[c] / n);
          o_temporal_var[size_t(x) * 3 + size_t(c)] = float(variance(t.temporal[c], t.temporal_a[c]));
        }
        o_temporal_failure[x] = float(double(t.failures) / n);
      }
    }
  }
  std::vector<std::vector<Sums>>().swap(bands_);
  std::vector<TemporalSums>().swap(temporal_sums_);
  GradientFilmBuffers b;
  b.primal = primal.take();
  b.dx = dx.take();
  b.dy = dy.take();
  b.direct = direct.take();
  b.primal_var = primal_var.take();
  b.dx_var = dx_var.take();
  b.dy_var = dy_var.take();
  b.shift_failure_rate = failure_rate.take();
  if (tc) {
    b.temporal = temporal.take();
    b.temporal_var = temporal_var.take();
    b.temporal_failure_rate = temporal_failure_rate.take();
  }
  if (!pairs_.empty()) resolve_pair_primal(spp, &b);
  std::vector<PairSums>().swap(pairs_);
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
