// Every instruction-set variant of the window solve's kernels
// (core/recon/poisson_kernels.h) gives the baseline's bits: stencil lines in
// both weight modes, spatial and temporal, at widths around the span and
// vector sizes, with dropped constraints breaking spans; and the two CG
// passes. The operator built on them is checked against an assembled matrix
// in reconstruct_exact_test.cpp.
#include "core/recon/poisson_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace gdvr {
namespace {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Nine rows of p (three frames × three lines), twelve weight rows and four
// mask rows of one width, with random values; mask bits mostly set so that
// most spans are uniform and some are not.
struct LineData {
  int width;
  std::vector<std::vector<float>> x, w;
  std::vector<std::vector<uint8_t>> masks;
  std::vector<uint8_t> uniform;

  LineData(int width_, std::mt19937& rng) : width(width_) {
    std::uniform_real_distribution<float> value(-2.0f, 3.0f), weight(0.0f, 1.5f);
    std::uniform_int_distribution<int> bit_pattern(0, 63);
    std::bernoulli_distribution dropped(0.01);
    x.assign(9, std::vector<float>(size_t(width)));
    for (auto& row : x)
      for (float& v : row) v = value(rng);
    w.assign(12, std::vector<float>(size_t(width)));
    for (auto& row : w)
      for (float& v : row) v = weight(rng);
    masks.assign(4, std::vector<uint8_t>(size_t(width), 63));
    for (auto& row : masks)
      for (uint8_t& m : row)
        if (dropped(rng)) m = uint8_t(bit_pattern(rng));
    const int spans = (width + kStencilSpan - 1) / kStencilSpan;
    uniform.assign(size_t(spans), 0);
    for (int s = 0; s < spans; ++s) {
      // Span s reads mask columns [s·span − 1, (s + 1)·span) ∩ [0, width − 1).
      const int a = s * kStencilSpan - 1 < 0 ? 0 : s * kStencilSpan - 1;
      const int b = (s + 1) * kStencilSpan < width - 1 ? (s + 1) * kStencilSpan : width - 1;
      bool same = true;
      for (const auto& row : masks)
        for (int i = a; i < b; ++i) same = same && row[size_t(i)] == row[size_t(a)];
      uniform[size_t(s)] = same;
    }
  }

  StencilLine line(bool masked, bool temporal, float* q) const {
    StencilLine l;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) l.x[a][b] = x[size_t(3 * a + b)].data();
    l.p = l.x[1][1];
    l.q = q;
    l.width = width;
    l.temporal = temporal;
    l.masked = masked;
    for (int k = 0; k < 4; ++k) l.mask[k] = masks[size_t(k)].data();
    l.uniform_spans = uniform.data();
    const float term_weight[6] = {0.04f, 1.0f, 1.0f, 0.7f, 0.35f, 0.35f};
    for (int k = 0; k < 6; ++k) l.term_weight[k] = term_weight[k];
    l.dropped_primal_weight = 0.0004f;
    for (int k = 0; k < 12; ++k) l.weight_rows[k] = w[size_t(k)].data();
    return l;
  }
};

TEST(PoissonKernelsTest, VariantsAreThoseTheCpuRuns) {
  const auto variants = poisson_kernel_variants();
  ASSERT_FALSE(variants.empty());
  EXPECT_STREQ(variants.front()->isa, "baseline");
  EXPECT_EQ(&poisson_kernels(), variants.back());
#if defined(__x86_64__)  // where core/CMakeLists.txt builds the AVX variants
  std::vector<std::string> expected{"baseline"};
  if (__builtin_cpu_supports("avx2")) expected.push_back("avx2");
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq"))
    expected.push_back("avx512");
  std::vector<std::string> got;
  for (const PoissonKernels* k : variants) got.push_back(k->isa);
  EXPECT_EQ(got, expected);
#endif
}

TEST(PoissonKernelsTest, StencilLinesMatchTheBaselineBitForBit) {
  const auto variants = poisson_kernel_variants();
  const PoissonKernels& base = *variants.front();
  std::mt19937 rng(7);
  int compared = 0;
  for (int width : {1, 2, 3, 15, 16, 17, 63, 64, 65, 66, 129, 200, 704}) {
    const LineData data(width, rng);
    for (bool masked : {true, false})
      for (bool temporal : {true, false}) {
        std::vector<float> q_base(size_t(width), -1.0f);
        const float dot_base = base.apply_line(data.line(masked, temporal, q_base.data()));
        // A finite, non-trivial line: the comparison means something.
        ASSERT_TRUE(std::isfinite(dot_base));
        ASSERT_NE(q_base[0], -1.0f);
        for (size_t v = 1; v < variants.size(); ++v) {
          std::vector<float> q(size_t(width), -2.0f);
          const float dot = variants[v]->apply_line(data.line(masked, temporal, q.data()));
          SCOPED_TRACE(std::string(variants[v]->isa) + " width " + std::to_string(width) +
                       (masked ? " masked" : " float weights") + (temporal ? " temporal" : " spatial"));
          EXPECT_TRUE(same_bits(dot, dot_base)) << dot << " vs " << dot_base;
          for (int i = 0; i < width; ++i) ASSERT_TRUE(same_bits(q[size_t(i)], q_base[size_t(i)])) << "column " << i;
          ++compared;
        }
      }
  }
  EXPECT_EQ(compared, 13 * 4 * int(variants.size() - 1));
}

TEST(PoissonKernelsTest, MaskedLineEqualsFloatWeightsOfTheSameConstants) {
  // The uniform-span shortcut must give what per-pixel weights give.
  std::mt19937 rng(11);
  const LineData data(300, rng);
  for (const PoissonKernels* k : poisson_kernel_variants()) {
    StencilLine masked = data.line(true, true, nullptr);
    std::vector<float> q_masked(300), q_float(300);
    masked.q = q_masked.data();
    k->apply_line(masked);
    // The float rows masked.* would give: bit set -> term weight, else 0
    // (primal: the dropped weight), for each of the twelve rows.
    const int term_of_row[12] = {0, 1, 2, 2, 3, 3, 4, 4, 5, 5, 5, 5};
    const int mask_of_row[12] = {0, 0, 0, 1, 0, 2, 0, 2, 0, 1, 2, 3};
    std::vector<std::vector<float>> rows(12, std::vector<float>(300));
    StencilLine flt = data.line(false, true, q_float.data());
    for (int r = 0; r < 12; ++r) {
      for (int i = 0; i < 300; ++i) {
        const bool on = (data.masks[size_t(mask_of_row[r])][size_t(i)] >> term_of_row[r]) & 1;
        rows[size_t(r)][size_t(i)] =
            on ? masked.term_weight[term_of_row[r]] : (r == 0 ? masked.dropped_primal_weight : 0.0f);
      }
      flt.weight_rows[r] = rows[size_t(r)].data();
    }
    k->apply_line(flt);
    for (int i = 0; i < 300; ++i)
      ASSERT_TRUE(same_bits(q_masked[size_t(i)], q_float[size_t(i)])) << k->isa << " column " << i;
  }
}

TEST(PoissonKernelsTest, CgPassesMatchTheBaselineBitForBit) {
  const auto variants = poisson_kernel_variants();
  const PoissonKernels& base = *variants.front();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> value(-1.0f, 1.0f), positive(0.1f, 2.0f);
  for (size_t n : {size_t(1), size_t(7), size_t(8), size_t(9), size_t(100), size_t(16384 + 5)}) {
    std::vector<float> r(n), q(n), M(n), x(n), p(n);
    for (size_t i = 0; i < n; ++i) r[i] = value(rng), q[i] = value(rng), M[i] = positive(rng), x[i] = value(rng),
                                    p[i] = value(rng);
    for (bool last : {false, true}) {
      auto rb = r, xb = x, pb = p;
      const PcgSums sb = base.update_residual(rb.data(), q.data(), M.data(), 0.37f, 0, n);
      base.update_solution(xb.data(), pb.data(), rb.data(), M.data(), 0.37f, 0.81f, last, 0, n);
      ASSERT_GT(sb.first, 0.0f);
      for (size_t v = 1; v < variants.size(); ++v) {
        auto rv = r, xv = x, pv = p;
        const PcgSums sv = variants[v]->update_residual(rv.data(), q.data(), M.data(), 0.37f, 0, n);
        variants[v]->update_solution(xv.data(), pv.data(), rv.data(), M.data(), 0.37f, 0.81f, last, 0, n);
        SCOPED_TRACE(std::string(variants[v]->isa) + " n " + std::to_string(n));
        EXPECT_TRUE(same_bits(sv.first, sb.first));
        EXPECT_TRUE(same_bits(sv.second, sb.second));
        for (size_t i = 0; i < n; ++i) {
          ASSERT_TRUE(same_bits(rv[i], rb[i]));
          ASSERT_TRUE(same_bits(xv[i], xb[i]));
          ASSERT_TRUE(same_bits(pv[i], pb[i]));
        }
      }
    }
  }
}

}  // namespace
}  // namespace gdvr
