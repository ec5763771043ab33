#include "core/recon/constraint_layout.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

namespace gdvr {

int64_t ConstraintLayout::total_non_finite() const {
  int64_t n = 0;
  for (int64_t v : non_finite) n += v;
  return n;
}

std::string ConstraintLayout::to_string() const {
  std::ostringstream s;
  s << grid.width << "x" << grid.height << "x" << grid.frames << " channels=" << channels;
  for (Term t : kAllTerms)
    if (present(t))
      s << " " << term_name(t) << "(non_finite=" << non_finite[term_index(t)] << " masked=" << masked[term_index(t)]
        << ")";
  return s.str();
}

ConstraintLayout build_constraint_layout(const GradientWindow& window, const PixelRect* counted) {
  ConstraintLayout L;
  L.grid = {window.width(), window.height(), window.size()};
  L.channels = window.channels();
  const Grid& g = L.grid;
  const int C = L.channels;
  L.targets = build_temporal_targets(window);
  // Targets decide which temporal constraints exist even where the stencil applies them.
  const bool follows_motion = !L.targets.next_offset.empty();
  for (Term term : kAllTerms) {
    const int k = term_index(term);
    bool any_buffer = false;
    for (int t = 0; t < g.frames; ++t) any_buffer |= window.frames[t]->has(term);
    if (!any_buffer) continue;
    std::vector<uint8_t>& valid = L.valid[k];
    valid.assign(g.size(), 0);
    std::atomic<int64_t> non_finite{0}, masked{0};
    tbb::parallel_for(0, g.frames, [&](int t) {
      const GradientFrame& f = *window.frames[t];
      if (!f.has(term)) return;
      if (is_temporal(term) && t + 1 >= g.frames) return;  // reaches outside the window
      const float* v = f.buffer(term).data().data();
      const float* var = f.has(term) && !f.variance(term).empty() ? f.variance(term).data().data() : nullptr;
      const std::vector<uint8_t>& user = f.mask(term);
      int64_t nf = 0, mk = 0;
      const int x_end = uses_x_neighbour(term) ? g.width - 1 : g.width;
      const int y_end = uses_y_neighbour(term) ? g.height - 1 : g.height;
      for (int y = 0; y < y_end; ++y)
        for (int x = 0; x < x_end; ++x) {
          const size_t p = size_t(y) * g.width + x;
          const bool count = !counted || counted->contains(x, y);
          if (!user.empty() && !user[p]) {
            mk += count;
            continue;
          }
          if (follows_motion && is_temporal(term)) {
            const size_t i = g.index(x, y, t);
            if (!L.targets.lands(i)) {
              mk += count;
              continue;
            }
            // The target's own right / lower neighbour must exist too.
            const int64_t q = int64_t(p) + L.targets.next_offset[i];
            if ((uses_x_neighbour(term) && q % g.width == g.width - 1) ||
                (uses_y_neighbour(term) && q / g.width == g.height - 1)) {
              mk += count;
              continue;
            }
          }
          bool finite = true;
          for (int c = 0; c < C; ++c) {
            finite &= std::isfinite(v[p * C + c]);
            if (var) finite &= std::isfinite(var[p * C + c]) && var[p * C + c] >= 0;
          }
          if (!finite) {
            nf += count;
            continue;
          }
          valid[g.index(x, y, t)] = 1;
        }
      non_finite += nf;
      masked += mk;
    });
    L.non_finite[k] = non_finite;
    L.masked[k] = masked;
    if (is_temporal(term)) L.temporal = true;
  }
  return L;
}

std::vector<uint8_t> pack_valid_bits(const ConstraintLayout& L) {
  std::vector<uint8_t> bits(L.grid.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, bits.size(), 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
    for (Term term : kAllTerms) {
      const std::vector<uint8_t>& valid = L.mask(term);
      if (valid.empty()) continue;
      const uint8_t bit = uint8_t(1u << term_index(term));
      for (size_t i = r.begin(); i != r.end(); ++i) bits[i] |= valid[i] ? bit : 0;
    }
  });
  return bits;
}

namespace {
void gather(const GradientWindow& window, const ConstraintLayout& L, Term term, int c, bool variance, Field* out) {
  const Grid& g = L.grid;
  const std::vector<uint8_t>& valid = L.mask(term);
  out->resize(g.size());
  if (valid.empty()) {
    std::fill(out->begin(), out->end(), 0.0f);
    return;
  }
  float* o = out->data();
  const int C = L.channels;
  tbb::parallel_for(0, g.frames, [&](int t) {
    const GradientFrame& f = *window.frames[t];
    const Image& img = variance ? f.variance(term) : f.buffer(term);
    const size_t base = size_t(t) * g.frame_size();
    if (img.empty()) {
      std::fill(o + base, o + base + g.frame_size(), 0.0f);
      return;
    }
    const float* v = img.data().data();
    for (size_t p = 0; p < g.frame_size(); ++p) o[base + p] = valid[base + p] ? v[p * C + c] : 0.0f;
  });
}

Field gather(const GradientWindow& window, const ConstraintLayout& L, Term term, int c, bool variance) {
  Field out;
  gather(window, L, term, c, variance, &out);
  return out;
}
}  // namespace

Field gather_term(const GradientWindow& window, const ConstraintLayout& layout, Term t, int c) {
  return gather(window, layout, t, c, /* variance = */ false);
}

void gather_term(const GradientWindow& window, const ConstraintLayout& layout, Term t, int c, Field* out) {
  gather(window, layout, t, c, /* variance = */ false, out);
}

Field gather_variance(const GradientWindow& window, const ConstraintLayout& layout, Term t, int c) {
  for (const auto& f : window.frames)
    if (!f->variance(t).empty()) return gather(window, layout, t, c, /* variance = */ true);
  return {};
}

Field gather_data_weight(const GradientWindow& window, const ConstraintLayout& layout) {
  if (std::none_of(window.frames.begin(), window.frames.end(), [](const auto& f) { return !f->data_weight.empty(); }))
    return {};
  const Grid& g = layout.grid;
  Field out(g.size(), 1.0f);
  tbb::parallel_for(0, g.frames, [&](int t) {
    const Image& w = window.frames[t]->data_weight;
    if (w.empty()) return;
    std::copy(w.data().begin(), w.data().end(), out.begin() + std::ptrdiff_t(size_t(t) * g.frame_size()));
  });
  return out;
}

}  // namespace gdvr
