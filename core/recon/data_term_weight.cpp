#include "core/recon/data_term_weight.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace gdvr {
namespace {

// Sums over boxes of (2r+1)² pixels, clipped at the image, by a summed-area table.
class BoxSums {
 public:
  BoxSums(const std::vector<double>& v, int w, int h) : w_(w), h_(h), s_(size_t(w + 1) * size_t(h + 1), 0.0) {
    for (int y = 0; y < h; ++y) {
      double row = 0;
      for (int x = 0; x < w; ++x) {
        row += v[size_t(y) * w + x];
        at(x + 1, y + 1) = at(x + 1, y) + row;
      }
    }
  }
  double sum(int x, int y, int r) const {
    const int x0 = std::max(0, x - r), x1 = std::min(w_, x + r + 1);
    const int y0 = std::max(0, y - r), y1 = std::min(h_, y + r + 1);
    return at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0);
  }

 private:
  double& at(int x, int y) { return s_[size_t(y) * (w_ + 1) + x]; }
  double at(int x, int y) const { return s_[size_t(y) * (w_ + 1) + x]; }
  int w_, h_;
  std::vector<double> s_;
};

}  // namespace

Expected<Image> data_term_weight(const Image& denoised, const Image& dx_a, const Image& dx_b, const Image& dy_a,
                                    const Image& dy_b, const DataTermWeightSettings& settings) {
  const int w = denoised.width(), h = denoised.height(), C = denoised.channels();
  for (const Image* im : {&dx_a, &dx_b, &dy_a, &dy_b})
    if (im->width() != w || im->height() != h || im->channels() != C)
      return invalid_argument("data term weight: the gradients' shape differs from the data term's");
  if (settings.radius < 0 || !(settings.max_multiplier >= 1))
    return invalid_argument("data term weight: radius must be >= 0 and max_multiplier >= 1");
  // Per pixel, channel means over its usable constraints (dx to the right,
  // dy below): (∇D − G_A)(∇D − G_B), whose mean is the squared bias of ∇D
  // (the passes' noise is independent), and (G_A − G_B)²/4, whose mean is
  // the variance of the gradient estimate (G_A + G_B)/2.
  std::vector<double> bias2(size_t(w) * h, 0.0), var(size_t(w) * h, 0.0), n(size_t(w) * h, 0.0);
  const float* d = denoised.data().data();
  auto add = [&](const Image& ga, const Image& gb, int x, int y, int dxo, int dyo) {
    const size_t p = size_t(y) * w + x, q = size_t(y + dyo) * w + (x + dxo);
    double bb = 0, vv = 0;
    for (int c = 0; c < C; ++c) {
      const double a = ga.data()[p * C + c], b = gb.data()[p * C + c];
      const double diff = double(d[q * C + c]) - double(d[p * C + c]);
      if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(diff)) return;
      bb += (diff - a) * (diff - b);
      vv += 0.25 * (a - b) * (a - b);
    }
    bias2[p] += bb / C;
    var[p] += vv / C;
    n[p] += 1;
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (x + 1 < w) add(dx_a, dx_b, x, y, 1, 0);
      if (y + 1 < h) add(dy_a, dy_b, x, y, 0, 1);
    }
  const BoxSums B(bias2, w, h), V(var, w, h), N(n, w, h);
  const double max_m = settings.max_multiplier;
  Image out(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double count = N.sum(x, y, settings.radius);
      double m = max_m;  // no usable gradient nearby: only the data term knows
      if (count > 0) {
        const double vm = V.sum(x, y, settings.radius) / count;
        const double excess = B.sum(x, y, settings.radius) / count;
        if (excess > 0) m = std::sqrt(vm / excess);
      }
      out.data()[size_t(y) * w + x] = float(std::clamp(std::isfinite(m) ? m : max_m, 1.0, max_m));
    }
  return out;
}

}  // namespace gdvr
