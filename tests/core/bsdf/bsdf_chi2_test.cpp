// Chi-square goodness-of-fit of bsdf_sample() against bsdf_pdf(), after the
// tests in Mitsuba (python/mitsuba/chi2.py) and pbrt-v3 (src/tests/bsdfs.cpp):
// sample directions into (theta, phi) bins, integrate the pdf over each bin by
// Gauss-Legendre quadrature, pool low-expectation bins, and compare. Dirac
// samples and failed samples share one extra cell whose expectation is the
// pdf's missing mass. Equal-angle bins rather than equal-cos bins keep the
// quadrature accurate for lobes as narrow as Beckmann alpha = 0.05 at the pole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "core/math/rng.h"
#include "tests/core/bsdf/bsdf_test_util.h"

namespace gdvr::testing {
namespace {

constexpr int kThetaBins = 40, kPhiBins = 80, kQuad = 4;
constexpr int kSamples = 200000;
constexpr double kSignificance = 0.01;

// Regularised upper incomplete gamma Q(a, x) (series / Lentz continued fraction).
double gamma_q(double a, double x) {
  if (x <= 0) return 1.0;
  double gln = std::lgamma(a);
  if (x < a + 1) {
    double ap = a, sum = 1.0 / a, del = sum;
    for (int n = 0; n < 10000; ++n) {
      ap += 1;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * 1e-15) break;
    }
    return 1.0 - sum * std::exp(-x + a * std::log(x) - gln);
  }
  double b = x + 1 - a, c = 1.0 / 1e-300, d = 1.0 / b, h = d;
  for (int i = 1; i < 10000; ++i) {
    double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < 1e-300) d = 1e-300;
    c = b + an / c;
    if (std::abs(c) < 1e-300) c = 1e-300;
    d = 1.0 / d;
    double del = d * c;
    h *= del;
    if (std::abs(del - 1) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - gln) * h;
}

void gauss_legendre(int n, std::vector<double>* x, std::vector<double>* w) {
  x->resize(n);
  w->resize(n);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), pp = 0;
    for (int it = 0; it < 100; ++it) {
      double p1 = 1, p2 = 0;
      for (int j = 1; j <= n; ++j) {
        double p3 = p2;
        p2 = p1;
        p1 = ((2 * j - 1) * z * p2 - (j - 1) * p3) / j;
      }
      pp = n * (z * p1 - p2) / (z * z - 1);
      double dz = p1 / pp;
      z -= dz;
      if (std::abs(dz) < 1e-15) break;
    }
    (*x)[i] = z;
    (*w)[i] = 2 / ((1 - z * z) * pp * pp);
  }
}

}  // namespace

namespace {

// Adaptive 2D Gauss-Legendre over one (theta, phi) cell: split into four while
// the split estimate disagrees. Narrow glossy lobes at grazing angles are only
// a few milliradians wide in phi, far narrower than a bin.
struct CellIntegrator {
  const BsdfCase& c;
  std::vector<double> gx, gw;

  double gl(double t0, double t1, double p0, double p1) const {
    double sum = 0;
    for (int a = 0; a < kQuad; ++a) {
      double theta = t0 + (t1 - t0) * (0.5 + 0.5 * gx[a]);
      double st = std::sin(theta), ct = std::cos(theta);
      for (int b = 0; b < kQuad; ++b) {
        double phi = p0 + (p1 - p0) * (0.5 + 0.5 * gx[b]);
        Vec3f wi(float(st * std::cos(phi)), float(st * std::sin(phi)), float(ct));
        sum += gw[a] * gw[b] * bsdf_pdf(c.bsdf, Vec2f(0.5f, 0.5f), c.wo, wi) * st;
      }
    }
    return sum * 0.25 * (t1 - t0) * (p1 - p0);
  }

  double adaptive(double t0, double t1, double p0, double p1, double whole, int depth) const {
    double tm = 0.5 * (t0 + t1), pm = 0.5 * (p0 + p1);
    double q[4] = {gl(t0, tm, p0, pm), gl(tm, t1, p0, pm), gl(t0, tm, pm, p1), gl(tm, t1, pm, p1)};
    double split = q[0] + q[1] + q[2] + q[3];
    if (depth >= 7 || std::abs(split - whole) <= 2e-8) return split;
    return adaptive(t0, tm, p0, pm, q[0], depth + 1) + adaptive(tm, t1, p0, pm, q[1], depth + 1) +
           adaptive(t0, tm, pm, p1, q[2], depth + 1) + adaptive(tm, t1, pm, p1, q[3], depth + 1);
  }
};

}  // namespace

// Integral of bsdf_pdf over every (theta, phi) bin; shared with the pdf-mass test.
std::vector<double> integrate_pdf_bins(const BsdfCase& c) {
  CellIntegrator integ{c, {}, {}};
  gauss_legendre(kQuad, &integ.gx, &integ.gw);
  const double dt = M_PI / kThetaBins, dp = 2 * M_PI / kPhiBins;
  std::vector<double> out(kThetaBins * kPhiBins, 0.0);
  for (int it = 0; it < kThetaBins; ++it)
    for (int ip = 0; ip < kPhiBins; ++ip) {
      double t0 = it * dt, t1 = t0 + dt, p0 = ip * dp, p1 = p0 + dp;
      out[it * kPhiBins + ip] = integ.adaptive(t0, t1, p0, p1, integ.gl(t0, t1, p0, p1), 0);
    }
  return out;
}

class Chi2Sampling : public ::testing::TestWithParam<BsdfCase> {};

TEST_P(Chi2Sampling, SamplingMatchesPdf) {
  const BsdfCase& c = GetParam();
  std::vector<double> expected = integrate_pdf_bins(c);
  std::vector<double> observed(expected.size(), 0.0);
  Pcg32 rng(0x9e3779b97f4a7c15ULL, std::hash<std::string>{}(c.name));
  int in_bins = 0;
  for (int i = 0; i < kSamples; ++i) {
    float u_lobe = rng.next_float();
    Vec2f u(rng.next_float(), rng.next_float());
    BsdfSample s;
    if (!bsdf_sample(c.bsdf, Vec2f(0.5f, 0.5f), c.wo, u_lobe, u, &s) || s.is_delta()) continue;
    double theta = std::acos(std::clamp(double(s.wi.z), -1.0, 1.0));
    double phi = std::atan2(double(s.wi.y), double(s.wi.x));
    if (phi < 0) phi += 2 * M_PI;
    int it = std::min(kThetaBins - 1, int(theta / M_PI * kThetaBins));
    int ip = std::min(kPhiBins - 1, int(phi / (2 * M_PI) * kPhiBins));
    observed[it * kPhiBins + ip] += 1;
    ++in_bins;
  }
  double mass = 0;
  for (double& e : expected) {
    mass += e;
    e *= kSamples;
  }
  // Dirac lobes and failed samples: the probability mass the pdf does not cover.
  expected.push_back(std::max(0.0, 1.0 - mass) * kSamples);
  observed.push_back(double(kSamples - in_bins));

  // Samples where the pdf is zero across a whole bin mean sampling and pdf disagree on the support.
  double outside = 0;
  for (size_t i = 0; i + 1 < expected.size(); ++i)
    if (expected[i] == 0.0) outside += observed[i];
  EXPECT_LE(outside, kSamples * 1e-4) << "samples where pdf() is zero";

  // Pool cells with expectation below 5 (sorted ascending) so the chi2 approximation holds.
  std::vector<size_t> order(expected.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double chi2 = 0, pool_e = 0, pool_o = 0;
  int cells = 0;
  for (size_t idx : order) {
    if (expected[idx] == 0.0 && observed[idx] == 0.0) continue;
    if (pool_e < 5.0) {
      pool_e += expected[idx];
      pool_o += observed[idx];
      continue;
    }
    chi2 += (observed[idx] - expected[idx]) * (observed[idx] - expected[idx]) / expected[idx];
    ++cells;
  }
  if (pool_e > 0) {
    chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
    ++cells;
  }
  ASSERT_GT(cells, 1);
  double p_value = gamma_q(0.5 * (cells - 1), 0.5 * chi2);
  // Sidak correction over all instantiated chi2 tests.
  static const size_t n_tests = density_cases().size();
  double alpha = 1.0 - std::pow(1.0 - kSignificance, 1.0 / double(n_tests));
  EXPECT_GT(p_value, alpha) << "chi2 = " << chi2 << " with " << cells - 1 << " dof; pdf mass " << mass;
}

// Every configuration with a density (Dirac-only BSDFs have no pdf to test against;
// BsdfDeltaOnly checks those).
INSTANTIATE_TEST_SUITE_P(Chi2, Chi2Sampling, ::testing::ValuesIn(density_cases()), ParamName());

}  // namespace gdvr::testing
