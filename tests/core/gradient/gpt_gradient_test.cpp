// Statistical tests of the G-PT estimators, parametrised over the shift
// mappings: the mean sampled gradient equals the finite difference of a
// converged PT image; cached-path Russian roulette leaves the mean unchanged;
// the L2 reconstruction converges to the PT image at about 1/spp.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/gradient/gpt_integrator.h"
#include "core/recon/reconstruct.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

using test::load_test_scene;

// Per-pixel mean and variance of the mean of some buffers over independent seeds.
struct SeedStats {
  std::vector<double> mean, var;  // [buffer][pixel][channel] flattened
};

using FilmBuffer = Image GradientFilmBuffers::*;

SeedStats buffer_stats(const test::TestScene& ts, const GptSettings& gpt, int spp, int seeds, uint64_t seed0,
                       const std::vector<FilmBuffer>& buffers) {
  FrameRenderSettings rs = ts.render;
  rs.spp = spp;
  const size_t n = size_t(rs.width) * rs.height * 3, m = buffers.size() * n;
  std::vector<double> sum(m, 0.0), sum_sq(m, 0.0);
  for (int s = 0; s < seeds; ++s) {
    rs.seed = seed0 + uint64_t(s) * 7919;
    auto r = render_frame_gpt(*ts.scene, rs, gpt, 0, {});
    EXPECT_TRUE(r.ok()) << r.status().to_string();
    if (!r.ok()) return {};
    for (size_t b = 0; b < buffers.size(); ++b) {
      const Image& img = r->buffers.*buffers[b];
      for (size_t k = 0; k < n; ++k) {
        sum[b * n + k] += img.data()[k];
        sum_sq[b * n + k] += double(img.data()[k]) * img.data()[k];
      }
    }
  }
  SeedStats st;
  st.mean.resize(m);
  st.var.resize(m);
  for (size_t k = 0; k < m; ++k) {
    st.mean[k] = sum[k] / seeds;
    st.var[k] = std::max(0.0, (sum_sq[k] - seeds * st.mean[k] * st.mean[k]) / (seeds - 1)) / seeds;
  }
  return st;
}

// dx then dy.
SeedStats gradient_stats(const test::TestScene& ts, const GptSettings& gpt, int spp, int seeds, uint64_t seed0) {
  return buffer_stats(ts, gpt, spp, seeds, seed0, {&GradientFilmBuffers::dx, &GradientFilmBuffers::dy});
}

struct ZStats {
  double mean_z2 = 0, aggregate_z = 0;
  int count = 0;
};

// z-scores of (a - b) with the variances va + vb over `buffers` images of w x h
// (for gradients: dx then dy, whose last column / row is undefined).
ZStats compare(int w, int h, const std::vector<double>& a, const std::vector<double>& va,
               const std::vector<double>& b, const std::vector<double>& vb, bool gradients = true) {
  ZStats z;
  double sum_d = 0, sum_v = 0;
  const size_t n = size_t(w) * h * 3;
  const int buffers = int(a.size() / n);
  for (int buf = 0; buf < buffers; ++buf)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (gradients && ((buf == 0 && x + 1 >= w) || (buf == 1 && y + 1 >= h))) continue;
        for (int c = 0; c < 3; ++c) {
          size_t k = buf * n + (size_t(y) * w + x) * 3 + c;
          double d = a[k] - b[k], v = va[k] + vb[k];
          if (!(v > 1e-12)) {
            EXPECT_NEAR(d, 0.0, 1e-4) << "noise-free pixel differs at " << x << "," << y;
            continue;
          }
          z.mean_z2 += d * d / v;
          sum_d += d;
          sum_v += v;
          ++z.count;
        }
      }
  z.mean_z2 /= std::max(1, z.count);
  z.aggregate_z = sum_v > 0 ? sum_d / std::sqrt(sum_v) : 0;
  return z;
}

struct SceneCase {
  const char* name;
  int w, h, spp, seeds;
  float diffuse_roughness;  // 10: every rough plate is glossy, so offsets use half-vector copies
};

class GptGradientTest : public ::testing::TestWithParam<ShiftMapping> {};

TEST_P(GptGradientTest, MeanGradientEqualsFiniteDifferenceOfConvergedPt) {
  for (SceneCase sc : {SceneCase{"cbox", 16, 16, 32, 12, 0.001f}, SceneCase{"veach-mis", 24, 14, 32, 12, 0.001f},
                       SceneCase{"veach-mis", 24, 14, 32, 12, 10.0f},
                       // Smooth plastic: the reconnection shift reconnects at its diffuse base.
                       SceneCase{"matpreview", 24, 18, 32, 12, 0.001f}}) {
    auto ts = load_test_scene(sc.name, sc.w, sc.h);
    ASSERT_TRUE(ts);
    const test::PtReference& ref = test::pt_reference(sc.name, sc.w, sc.h, 4096);
    const size_t n = size_t(sc.w) * sc.h * 3;
    std::vector<double> fd(2 * n, 0.0), fd_var(2 * n, 0.0);
    for (int y = 0; y < sc.h; ++y)
      for (int x = 0; x < sc.w; ++x)
        for (int c = 0; c < 3; ++c) {
          size_t k = (size_t(y) * sc.w + x) * 3 + c;
          if (x + 1 < sc.w) {
            fd[k] = double(ref.indirect.at(x + 1, y, c)) - ref.indirect.at(x, y, c);
            fd_var[k] = double(ref.variance.at(x + 1, y, c)) + ref.variance.at(x, y, c);
          }
          if (y + 1 < sc.h) {
            fd[n + k] = double(ref.indirect.at(x, y + 1, c)) - ref.indirect.at(x, y, c);
            fd_var[n + k] = double(ref.variance.at(x, y + 1, c)) + ref.variance.at(x, y, c);
          }
        }
    GptSettings gpt = GptSettings::defaults_for(GetParam());
    gpt.diffuse_roughness = sc.diffuse_roughness;
    SeedStats g = gradient_stats(*ts, gpt, sc.spp, sc.seeds, 11);
    ASSERT_FALSE(g.mean.empty());
    ZStats z = compare(sc.w, sc.h, g.mean, g.var, fd, fd_var);
    std::printf("[ gradient ] %s %s (diffuse above roughness %g): mean z^2 %.3f over %d, aggregate z %.2f\n",
                sc.name, shift_mapping_name(GetParam()), sc.diffuse_roughness, z.mean_z2, z.count, z.aggregate_z);
    // Student t with seeds-1 dof: E[z^2] = 11/9; a biased shift shows as a clear excess.
    EXPECT_LT(z.mean_z2, 1.8) << sc.name;
    EXPECT_LT(std::abs(z.aggregate_z), 4.5) << sc.name;
  }
}

// The primal's mean over 12 seeds at 16 spp against the converged PT on a
// 16x12 `name`, by per-pixel z-scores; `label` names the variant in messages.
void expect_primal_mean_matches_pt(const char* name, const GptSettings& gpt, uint64_t seed0, const std::string& label,
                                   double max_mean_z2 = 1.8) {
  const int w = 16, h = 12;
  auto ts = load_test_scene(name, w, h);
  ASSERT_TRUE(ts);
  const test::PtReference& ref = test::pt_reference(name, w, h, 4096);
  const size_t n = size_t(w) * h * 3;
  std::vector<double> pt(ref.indirect.data().begin(), ref.indirect.data().begin() + long(n));
  std::vector<double> pt_var(ref.variance.data().begin(), ref.variance.data().begin() + long(n));
  SeedStats p = buffer_stats(*ts, gpt, 16, 12, seed0, {&GradientFilmBuffers::primal});
  ASSERT_FALSE(p.mean.empty());
  ZStats z = compare(w, h, p.mean, p.var, pt, pt_var, /* gradients = */ false);
  std::printf("[ primal ] %s %s %s: mean z^2 %.3f over %d, aggregate z %.2f\n", name, shift_mapping_name(gpt.shift),
              label.c_str(), z.mean_z2, z.count, z.aggregate_z);
  EXPECT_LT(z.mean_z2, max_mean_z2) << name << " " << label;
  EXPECT_LT(std::abs(z.aggregate_z), 4.5) << name << " " << label;
}

// The default shared sub-pixel position (GptSettings::shared_jitter) changes
// the base paths' camera rays, not what they estimate: the primal's mean over
// seeds equals the converged PT image, and so it does with positions per pixel.
TEST_P(GptGradientTest, PrimalMeanEqualsConvergedPtWithSharedOrOwnSubPixelPositions) {
  for (const char* name : {"cbox", "veach-mis"})
    for (bool shared : {true, false}) {
      GptSettings gpt = GptSettings::defaults_for(GetParam());
      gpt.shared_jitter = shared;
      expect_primal_mean_matches_pt(name, gpt, 31, std::string("shared_jitter=") + (shared ? "on" : "off"));
    }
}

// The MIS-weighted pair primal (GptSettings::pair_primal) is unbiased with
// and without cached-path RR (its 1/q correction). With the shared sub-pixel
// position neighbouring pixels' pair estimates share first hits, so their z
// are correlated and the mean z^2 over pixels scatters more between seed sets
// (0.9-2.4 over three sets, aggregate |z| < 1.7); with positions per pixel
// it behaves as the plain primal's (0.9-1.3).
TEST_P(GptGradientTest, PairPrimalMeanEqualsConvergedPtWithAndWithoutRoulette) {
  for (const char* name : {"cbox", "veach-mis"})
    for (bool rr : {true, false})
      for (bool shared : {true, false}) {
        GptSettings gpt = GptSettings::defaults_for(GetParam());
        gpt.cached_rr = rr;
        gpt.pair_primal = true;
        gpt.shared_jitter = shared;
        expect_primal_mean_matches_pt(name, gpt, 913,
                                      std::string("pair primal, cached_rr=") + (rr ? "on" : "off") +
                                          ", shared_jitter=" + (shared ? "on" : "off"),
                                      shared ? 3.0 : 1.8);
      }
}

TEST_P(GptGradientTest, CachedPathRouletteLeavesTheMeanUnchanged) {
  auto ts = load_test_scene("cbox", 16, 16);
  ASSERT_TRUE(ts);
  GptSettings on = GptSettings::defaults_for(GetParam()), off = on;
  on.cached_rr = true;
  off.cached_rr = false;
  SeedStats a = gradient_stats(*ts, on, 16, 12, 101), b = gradient_stats(*ts, off, 16, 12, 5003);
  ASSERT_FALSE(a.mean.empty());
  ASSERT_FALSE(b.mean.empty());
  ZStats z = compare(16, 16, a.mean, a.var, b.mean, b.var);
  std::printf("[ cached rr ] %s: mean z^2 %.3f over %d, aggregate z %.2f\n", shift_mapping_name(GetParam()),
              z.mean_z2, z.count, z.aggregate_z);
  EXPECT_LT(z.mean_z2, 1.8);
  EXPECT_LT(std::abs(z.aggregate_z), 4.5);
}

TEST_P(GptGradientTest, ReconstructionConvergesToPtAboutAsOneOverSpp) {
  const int w = 24, h = 24;
  auto ts = load_test_scene("cbox", w, h);
  ASSERT_TRUE(ts);
  FrameRenderSettings rs = ts->render;
  const test::PtReference& ref = test::pt_reference("cbox", w, h, 4096);  // indirect part: what is solved for
  GptSettings gpt = GptSettings::defaults_for(GetParam());
  gpt.recon.method = ReconMethod::kL2;
  gpt.recon.l2_tolerance = 1e-7;  // solver bias far below the noise
  gpt.recon.l2_max_iterations = 2000;
  double err[2] = {0, 0};
  const int spps[2] = {4, 64};
  for (int i = 0; i < 2; ++i) {
    // Average the error over a few seeds: relMSE of one image is itself noisy.
    const int seeds = 4;
    for (int s = 0; s < seeds; ++s) {
      rs.spp = spps[i];
      rs.seed = 77 + uint64_t(s);
      auto r = render_frame_gpt(*ts->scene, rs, gpt, 0, {});
      ASSERT_TRUE(r.ok());
      GradientFrame gf;
      gf.buffer(Term::kPrimal) = r->buffers.primal;
      gf.buffer(Term::kDx) = r->buffers.dx;
      gf.buffer(Term::kDy) = r->buffers.dy;
      auto rec = reconstruct_frame(gf, gpt.recon);
      ASSERT_TRUE(rec.ok()) << rec.status().to_string();
      const Image& img = rec->frames.front();
      EXPECT_TRUE(test::all_finite(img));
      err[i] += test::rel_mse(img, ref.indirect) / seeds;
    }
  }
  const double ratio = err[0] / err[1];
  std::printf("[ convergence ] %s: relMSE %.5f at %d spp, %.5f at %d spp, ratio %.2f (ideal %d)\n",
              shift_mapping_name(GetParam()), err[0], spps[0], err[1], spps[1], ratio, spps[1] / spps[0]);
  EXPECT_GT(ratio, 8.0);
  EXPECT_LT(ratio, 32.0);
}

INSTANTIATE_TEST_SUITE_P(Gpt, GptGradientTest,
                         ::testing::Values(ShiftMapping::kReplay, ShiftMapping::kReconnect, ShiftMapping::kHybrid),
                         [](const auto& info) { return std::string(shift_mapping_name(info.param)); });

}  // namespace
}  // namespace gdvr
