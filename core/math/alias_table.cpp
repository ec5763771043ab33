#include "core/math/alias_table.h"

#include <algorithm>
#include <cmath>

namespace gdvr {

AliasSample sample_alias(const AliasSlot* slots, size_t n, float u) {
  AliasSample s;
  if (n == 0) return s;
  const double scaled = double(u) * double(n);
  const size_t k = std::min(n - 1, size_t(scaled));
  const double frac = std::clamp(scaled - double(k), 0.0, 1.0);
  const AliasSlot& slot = slots[k];
  double r;
  if (frac < double(slot.q)) {
    s.index = k;
    s.pmf = slot.pmf;
    r = frac / double(slot.q);
  } else {
    s.index = slot.alias;
    s.pmf = slot.alias_pmf;
    r = slot.q < 1.0f ? (frac - double(slot.q)) / (1.0 - double(slot.q)) : 0.0;
  }
  s.u_remapped = float(std::clamp(r, 0.0, double(0x1.fffffep-1f)));
  return s;
}

double build_alias_table(const float* weights, size_t n, std::vector<AliasSlot>* slots) {
  const size_t first = slots->size();
  slots->resize(first + n);
  AliasSlot* out = slots->data() + first;
  std::vector<double> w(n);
  double total = 0;
  for (size_t i = 0; i < n; ++i) {
    w[i] = (std::isfinite(weights[i]) && weights[i] > 0) ? double(weights[i]) : 0.0;
    total += w[i];
  }
  if (!(total > 0)) return 0.0;  // slots stay zero: pmf 0 everywhere

  // Vose's method in double: scaled probabilities n p_i, split into those
  // below and above the mean; each small slot is topped up from a large one.
  std::vector<double> scaled(n);
  std::vector<uint32_t> small, large;
  for (size_t i = 0; i < n; ++i) {
    out[i].pmf = float(w[i] / total);
    scaled[i] = w[i] / total * double(n);
    (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
  }
  uint32_t last_positive = 0;
  for (size_t i = 0; i < n; ++i)
    if (w[i] > 0) last_positive = uint32_t(i);
  while (!small.empty() && !large.empty()) {
    const uint32_t s = small.back(), l = large.back();
    small.pop_back();
    out[s].q = float(scaled[s]);
    out[s].alias = l;
    scaled[l] -= 1.0 - scaled[s];
    if (scaled[l] < 1.0) {
      large.pop_back();
      small.push_back(l);
    }
  }
  // What is left has scaled probability 1 up to rounding: it keeps its slot,
  // unless rounding left a zero-weight bin here, which must never be chosen.
  for (const auto* rest : {&small, &large}) {
    for (uint32_t i : *rest) {
      out[i].q = w[i] > 0 ? 1.0f : 0.0f;
      out[i].alias = w[i] > 0 ? i : last_positive;
    }
  }
  for (size_t i = 0; i < n; ++i) out[i].alias_pmf = out[out[i].alias].pmf;
  return total;
}

}  // namespace gdvr
