// Known values of the Fresnel equations and normalisation of the microfacet
// distributions (Walter et al. 2007 eq. 4; Heitz 2014 eq. 2 for visible normals).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>

#include "core/bsdf/fresnel.h"
#include "core/bsdf/microfacet.h"

namespace gdvr {
namespace {

TEST(FresnelDielectric, NormalIncidence) {
  for (float eta : {1.1f, 1.333f, 1.5f, 2.4f}) {
    float expect = sqr((eta - 1) / (eta + 1));
    EXPECT_NEAR(fresnel_dielectric(1.0f, eta).f, expect, 1e-6f);
    EXPECT_NEAR(fresnel_dielectric(-1.0f, eta).f, expect, 1e-6f);  // same from inside
  }
}

TEST(FresnelDielectric, TotalInternalReflectionAndSpecialCases) {
  // From inside glass beyond the critical angle (sin > 1 / 1.5).
  EXPECT_EQ(fresnel_dielectric(-0.3f, 1.5f).f, 1.0f);
  EXPECT_EQ(fresnel_dielectric(0.0f, 1.5f).f, 1.0f);  // grazing
  EXPECT_EQ(fresnel_dielectric(0.5f, 1.0f).f, 0.0f);  // index-matched
}

TEST(FresnelDielectric, RefractionObeysSnell) {
  float eta = 1.5f, cos_i = 0.6f;
  FresnelResult r = fresnel_dielectric(cos_i, eta);
  Vec3f w(0.8f, 0.0f, cos_i);
  Vec3f t = refract_local(w, r.cos_theta_t, r.eta_ti);
  EXPECT_NEAR(length(t), 1.0f, 1e-5f);
  EXPECT_LT(t.z, 0.0f);
  EXPECT_NEAR(std::sqrt(1 - t.z * t.z) * eta, 0.8f, 1e-5f);
  EXPECT_FLOAT_EQ(r.eta_it, 1.5f);
}

TEST(FresnelConductor, ReducesToDielectricForZeroK) {
  for (float c : {1.0f, 0.7f, 0.3f, 0.05f})
    EXPECT_NEAR(fresnel_conductor(c, 1.5f, 0.0f), fresnel_dielectric(c, 1.5f).f, 1e-5f);
}

TEST(FresnelConductor, NoneIsOne) {
  for (float c : {1.0f, 0.5f, 0.01f, 0.0f}) EXPECT_NEAR(fresnel_conductor(c, 0.0f, 1.0f), 1.0f, 1e-6f);
}

TEST(FresnelDiffuse, MatchesHemisphericalIntegral) {
  for (float eta : {1.33f, 1.5f, 1.9f, 1.0f / 1.5f}) {
    double sum = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      double mu = (i + 0.5) / n;
      sum += fresnel_dielectric(float(mu), eta).f * mu;
    }
    EXPECT_NEAR(fresnel_diffuse_reflectance(eta), 2 * sum / n, 0.01) << eta;
  }
}

struct DistrCase {
  MicrofacetType type;
  float au, av;
};

// e.g. "beckmann_030_030", for test names and gtest's value printer.
std::string distr_name(const DistrCase& c) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%s_%03d_%03d", c.type == MicrofacetType::kBeckmann ? "beckmann" : "ggx",
                int(std::lround(c.au * 100)), int(std::lround(c.av * 100)));
  return buf;
}
void PrintTo(const DistrCase& c, std::ostream* os) { *os << distr_name(c); }

class MicrofacetNorm : public ::testing::TestWithParam<DistrCase> {};

// Integral over the hemisphere by midpoint rule in (theta, phi).
template <typename F>
double integrate_hemisphere(F f, int nt = 800, int np = 400) {
  double sum = 0, dt = 0.5 * M_PI / nt, dp = 2 * M_PI / np;
  for (int i = 0; i < nt; ++i) {
    double t = (i + 0.5) * dt;
    for (int j = 0; j < np; ++j) {
      double p = (j + 0.5) * dp;
      Vec3f m(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)), float(std::cos(t)));
      sum += f(m) * std::sin(t);
    }
  }
  return sum * dt * dp;
}

TEST_P(MicrofacetNorm, ProjectedAreaIsOne) {
  DistrCase c = GetParam();
  MicrofacetDistribution d(c.type, c.au, c.av, true);
  EXPECT_NEAR(integrate_hemisphere([&](Vec3f m) { return d.eval(m) * m.z; }), 1.0, 5e-3);
}

TEST_P(MicrofacetNorm, VisibleNormalsIntegrateToOne) {
  DistrCase c = GetParam();
  MicrofacetDistribution d(c.type, c.au, c.av, true);
  for (float z : {0.9f, 0.4f}) {
    Vec3f wi(std::sqrt(1 - z * z), 0, z);
    // Smith: integral of G1(wi, m) max(0, wi.m) D(m) dm = cos(theta_i), exactly
    // with the exact G1 (Mitsuba's rational Beckmann fit is off by up to 0.35 %).
    double v = integrate_hemisphere([&](Vec3f m) { return d.pdf(wi, m); });
    EXPECT_NEAR(v, 1.0, 2e-3) << z;
  }
}

INSTANTIATE_TEST_SUITE_P(Microfacet, MicrofacetNorm,
                         ::testing::Values(DistrCase{MicrofacetType::kBeckmann, 0.3f, 0.3f},
                                           DistrCase{MicrofacetType::kGGX, 0.3f, 0.3f},
                                           DistrCase{MicrofacetType::kBeckmann, 0.5f, 0.2f},
                                           DistrCase{MicrofacetType::kGGX, 0.6f, 0.15f}),
                         [](const ::testing::TestParamInfo<DistrCase>& i) { return distr_name(i.param); });

TEST(MicrofacetBeckmann, SmithG1MatchesExactFormula) {
  // G1 = 1 / (1 + Lambda(a)), Lambda(a) = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi)),
  // a = 1 / (alpha tan theta) (Walter et al. 2007 eq. 27), in long double here.
  const float alpha = 0.3f;
  MicrofacetDistribution d(MicrofacetType::kBeckmann, alpha, alpha, true);
  // G1 is evaluated in float: a dense sweep of cos(theta) over the grazing
  // range (Lambda large), the cancelling range (a in 2..9) and near normal.
  for (int i = 1; i < 4000; ++i) {
    const float z = float(i) / 4000.0f;
    const float x = std::sqrt(1 - z * z);
    const Vec3f v(x, 0, z);
    // From the float vector itself, so only smith_g1's own rounding is measured.
    long double a = (long double)v.z / ((long double)alpha * (long double)v.x);
    long double lambda = -0.5L * std::erfc(a) + std::exp(-a * a) / (2.0L * a * std::sqrt(3.14159265358979323846L));
    ASSERT_NEAR(d.smith_g1(v, Vec3f(0, 0, 1)), double(1.0L / (1.0L + lambda)), 2e-7) << z;
  }
  // Back-facing microfacets are never visible.
  EXPECT_EQ(d.smith_g1(Vec3f(0.6f, 0, 0.8f), normalize(Vec3f(-1, 0, 0.1f))), 0.0f);
}

TEST(MicrofacetErfinv, InvertsErf) {
  for (float x : {-0.999f, -0.5f, 0.0f, 0.3f, 0.9f, 0.99999f}) EXPECT_NEAR(std::erf(erfinv(x)), x, 2e-6f);
}

TEST(MicrofacetWarp, ConcentricDiskStaysInDisk) {
  for (float a : {0.0f, 0.25f, 0.5f, 0.99f})
    for (float b : {0.0f, 0.5f, 0.75f, 1.0f}) {
      Vec2f p = square_to_uniform_disk_concentric(Vec2f(a, b));
      EXPECT_LE(p.x * p.x + p.y * p.y, 1.0f + 1e-5f);
    }
}

}  // namespace
}  // namespace gdvr
