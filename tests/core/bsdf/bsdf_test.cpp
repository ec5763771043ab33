// Properties of the BSDFs over the configurations of bsdf_test_util.h, each
// instantiated only over the configurations it applies to: sample() consistent
// with eval()/pdf() and pdf mass <= 1 (with a density), Dirac samples invisible
// to eval()/pdf() (Dirac-only), reciprocity (reflection-only), and energy
// conservation and finite outputs for degenerate inputs (all).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "core/bsdf/conductor_presets.h"
#include "core/bsdf/fresnel.h"
#include "core/math/rng.h"
#include "tests/core/bsdf/bsdf_test_util.h"

namespace gdvr::testing {

std::vector<double> integrate_pdf_bins(const BsdfCase& c);  // bsdf_chi2_test.cpp

namespace {

const Vec2f kUv(0.5f, 0.5f);

// The same BSDF with white (albedo 1) parameters, for energy tests.
Bsdf whitened(Bsdf b) {
  b.reflectance = Texture::constant(Rgb(1.0f));
  b.specular_reflectance = Texture::constant(Rgb(1.0f));
  b.specular_transmittance = Texture::constant(Rgb(1.0f));
  b.eta = Rgb(0.0f);  // conductor "none"
  b.k = Rgb(1.0f);
  b.finalize();
  return b;
}

}  // namespace

// ---- Configurations with a diffuse or glossy lobe (a density) ----

class BsdfDensity : public ::testing::TestWithParam<BsdfCase> {};

TEST_P(BsdfDensity, SampleWeightIsEvalOverPdf) {
  const BsdfCase& c = GetParam();
  Pcg32 rng(7, std::hash<std::string>{}(c.name));
  int checked = 0, bad = 0;
  for (int i = 0; i < 4000; ++i) {
    BsdfSample s;
    if (!bsdf_sample(c.bsdf, kUv, c.wo, rng.next_float(), Vec2f(rng.next_float(), rng.next_float()), &s)) continue;
    ASSERT_TRUE(is_finite(s.weight) && std::isfinite(s.pdf) && s.pdf > 0);
    EXPECT_NEAR(length(s.wi), 1.0f, 1e-4f);
    // Dirac lobes (plastic's specular coat) are invisible to eval()/pdf(); the
    // non-Dirac lobes are not, so their samples are compared below.
    if (s.is_delta()) continue;
    BsdfEval e = bsdf_eval_pdf(c.bsdf, kUv, c.wo, s.wi);
    EXPECT_EQ(e.pdf, bsdf_pdf(c.bsdf, kUv, c.wo, s.wi));
    ++checked;
    float pdf_err = std::abs(e.pdf - s.pdf) / std::max(s.pdf, 1e-3f);
    Rgb expect = e.value / e.pdf;
    float w_err = 0;
    for (int ch = 0; ch < 3; ++ch)
      w_err = std::max(w_err, std::abs(expect[ch] - s.weight[ch]) / std::max(1e-3f, std::abs(s.weight[ch])));
    if (!(pdf_err < 2e-3f && w_err < 2e-3f)) {
      if (++bad <= 3)
        ADD_FAILURE() << "wi=(" << s.wi.x << "," << s.wi.y << "," << s.wi.z << ") pdf " << s.pdf << " vs " << e.pdf
                      << ", weight " << s.weight.r << " vs " << expect.r;
    }
  }
  // (No test configuration is a one-sided reflector seen from below.)
  EXPECT_GT(checked, 100);
}

TEST_P(BsdfDensity, PdfMassAtMostOne) {
  const BsdfCase& c = GetParam();
  double mass = 0;
  for (double v : integrate_pdf_bins(c)) mass += v;
  EXPECT_LE(mass, 1.0 + 2e-3);
  if (c.bsdf.type == BsdfType::kDiffuse && (c.wo.z > 0 || c.bsdf.two_sided)) {
    EXPECT_NEAR(mass, 1.0, 1e-3);
  }
  if (c.bsdf.type == BsdfType::kRoughDielectric && c.bsdf.alpha_u <= 0.2f && c.wo.z > 0.3f) {
    EXPECT_NEAR(mass, 1.0, 2e-2);  // both lobes; little leaks past the horizon (from inside, refraction spreads and more is lost)
  }
}

INSTANTIATE_TEST_SUITE_P(Bsdf, BsdfDensity, ::testing::ValuesIn(density_cases()), ParamName());

// ---- Configurations with only Dirac lobes ----

class BsdfDeltaOnly : public ::testing::TestWithParam<BsdfCase> {};

TEST_P(BsdfDeltaOnly, SamplesAreDiracAndInvisibleToEvalPdf) {
  const BsdfCase& c = GetParam();
  Pcg32 rng(7, std::hash<std::string>{}(c.name));
  int sampled = 0;
  for (int i = 0; i < 4000; ++i) {
    BsdfSample s;
    if (!bsdf_sample(c.bsdf, kUv, c.wo, rng.next_float(), Vec2f(rng.next_float(), rng.next_float()), &s)) continue;
    ++sampled;
    ASSERT_TRUE(is_finite(s.weight) && std::isfinite(s.pdf) && s.pdf > 0);
    EXPECT_NEAR(length(s.wi), 1.0f, 1e-4f);
    ASSERT_TRUE(s.is_delta()) << "lobe " << s.lobe;
    BsdfEval e = bsdf_eval_pdf(c.bsdf, kUv, c.wo, s.wi);
    EXPECT_EQ(e.pdf, 0.0f);
    EXPECT_EQ(bsdf_pdf(c.bsdf, kUv, c.wo, s.wi), 0.0f);
    EXPECT_EQ(average(e.value), 0.0f);
  }
  EXPECT_EQ(sampled, 4000);  // every test configuration is lit from a side it reflects or refracts
}

INSTANTIATE_TEST_SUITE_P(Bsdf, BsdfDeltaOnly, ::testing::ValuesIn(delta_only_cases()), ParamName());

// ---- Every configuration ----

class BsdfProperties : public ::testing::TestWithParam<BsdfCase> {};

TEST_P(BsdfProperties, EnergyConservation) {
  const BsdfCase& c = GetParam();
  Bsdf white = whitened(c.bsdf);
  Pcg32 rng(11, std::hash<std::string>{}(c.name));
  const int n = 100000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    BsdfSample s;
    double w = 0;
    if (bsdf_sample(white, kUv, c.wo, rng.next_float(), Vec2f(rng.next_float(), rng.next_float()), &s)) {
      w = average(s.weight);
      // Undo the radiance compression eta_ti^2 of refraction: it is not albedo.
      if (s.lobe & kLobeTransmission) w *= double(s.eta) * s.eta;
    }
    sum += w;
    sum2 += w * w;
  }
  double mean = sum / n, stderr_ = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
  EXPECT_LE(mean, 1.0 + 0.01 + 5 * stderr_);
  bool front = c.wo.z > 0 || c.bsdf.two_sided;
  if (c.bsdf.type == BsdfType::kDiffuse && front) {
    EXPECT_NEAR(mean, 1.0, 1e-6);
  }
  if ((c.bsdf.type == BsdfType::kConductor || c.bsdf.type == BsdfType::kDielectric ||
       c.bsdf.type == BsdfType::kThinDielectric) && (front || c.bsdf.has_lobe(kLobeTransmission))) {
    EXPECT_NEAR(mean, 1.0, 1e-4);
  }
  // White plastic: F + (1 - F) (1 - Fdr_ext) / (eta^2 (1 - Fdr_int)) = 1 up to the Fdr fits.
  if (c.bsdf.type == BsdfType::kPlastic && front) {
    EXPECT_NEAR(mean, 1.0, 0.015);
  }
}

TEST_P(BsdfProperties, FiniteForDegenerateInputs) {
  Bsdf bsdf = GetParam().bsdf;
  std::vector<Bsdf> variants = {bsdf};
  if (bsdf.type == BsdfType::kRoughConductor || bsdf.type == BsdfType::kRoughDielectric ||
      bsdf.type == BsdfType::kRoughPlastic) {
    Bsdf smooth = bsdf;
    smooth.alpha_u = smooth.alpha_v = 1e-4f;
    smooth.finalize();
    variants.push_back(smooth);
    Bsdf zero = bsdf;
    zero.alpha_u = zero.alpha_v = 0.0f;  // clamped to 1e-4 like Mitsuba
    zero.finalize();
    variants.push_back(zero);
  }
  const std::vector<Vec3f> dirs = {Vec3f(1, 0, 0),  Vec3f(0, 0, 1), Vec3f(0, 0, -1), Vec3f(0.6f, 0.8f, 0),
                                   GetParam().wo,   -GetParam().wo, Vec3f(0, 1e-7f, 1), Vec3f(0, 0, 0)};
  const float us[] = {0.0f, 1e-7f, 0.5f, 1.0f - 1e-7f, std::nextafter(1.0f, 0.0f)};
  for (const Bsdf& b : variants)
    for (Vec3f wo : dirs) {
      for (Vec3f wi : dirs) {
        BsdfEval e = bsdf_eval_pdf(b, kUv, wo, wi);
        ASSERT_TRUE(is_finite(e.value) && std::isfinite(e.pdf)) << wo.x << "," << wo.y << "," << wo.z;
        ASSERT_GE(e.pdf, 0.0f);
        ASSERT_GE(std::min(e.value.r, std::min(e.value.g, e.value.b)), 0.0f);
      }
      for (float u0 : us)
        for (float u1 : us) {
          BsdfSample s;
          if (bsdf_sample(b, kUv, wo, u0, Vec2f(u1, 1.0f - u1), &s)) {
            ASSERT_TRUE(is_finite(s.weight) && std::isfinite(s.pdf) && is_finite(s.wi));
            ASSERT_GT(s.pdf, 0.0f);
          }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Bsdf, BsdfProperties, ::testing::ValuesIn(all_bsdf_cases()), ParamName());

// ---- Reflection-only configurations with a density ----
// Reciprocity does not depend on the test's incident angle, so it is
// parametrised by configuration; it draws as many direction pairs as the
// former one run per angle (up to 5 angles x 2000 pairs) did.

class BsdfReciprocity : public ::testing::TestWithParam<BsdfConfig> {};

TEST_P(BsdfReciprocity, ReciprocityOfReflection) {
  const BsdfConfig& c = GetParam();
  Pcg32 rng(3, std::hash<std::string>{}(c.name));
  for (int i = 0; i < 10000; ++i) {
    Vec3f a = direction_with_cos(0.02f + 0.98f * rng.next_float(), 2 * kPi * rng.next_float());
    Vec3f b = direction_with_cos(0.02f + 0.98f * rng.next_float(), 2 * kPi * rng.next_float());
    Rgb fab = bsdf_eval(c.bsdf, kUv, a, b) / b.z, fba = bsdf_eval(c.bsdf, kUv, b, a) / a.z;
    for (int ch = 0; ch < 3; ++ch)
      ASSERT_NEAR(fab[ch], fba[ch], 2e-3f * std::max(1.0f, std::abs(fab[ch]))) << "channel " << ch;
  }
}

INSTANTIATE_TEST_SUITE_P(Bsdf, BsdfReciprocity, ::testing::ValuesIn(reflection_only_density_configs()),
                         ParamName());

// ---- Non-parametrised checks ----

TEST(BsdfConductor, NoneIsPerfectMirror) {
  Bsdf b;
  b.type = BsdfType::kConductor;
  ASSERT_TRUE(lookup_conductor("none", &b.eta, &b.k));
  b.finalize();
  for (float z : {1.0f, 0.5f, 0.05f}) {
    BsdfSample s;
    ASSERT_TRUE(bsdf_sample(b, kUv, direction_with_cos(z), 0.3f, Vec2f(0.2f, 0.7f), &s));
    EXPECT_NEAR(s.weight.r, 1.0f, 1e-5f);
    EXPECT_NEAR(s.weight.b, 1.0f, 1e-5f);
    EXPECT_NEAR(s.wi.z, z, 1e-6f);
    EXPECT_TRUE(s.lobe == kLobeDeltaReflection);
  }
}

TEST(BsdfConductor, PresetsKnown) {
  Rgb eta, k;
  for (const char* name : {"Au", "Ag", "Al", "Cu", "Cr", "W", "Hg", "Ni_palik", "a-C", "TiN"}) {
    EXPECT_TRUE(lookup_conductor(name, &eta, &k)) << name;
    EXPECT_GT(k.g, 0.5f) << name;
  }
  EXPECT_TRUE(lookup_conductor("Cu", &eta, &k));
  EXPECT_NEAR(eta.r, 0.200438f, 1e-5f);  // the value veach-mis spells out
  EXPECT_NEAR(k.b, 2.14219f, 1e-5f);
  EXPECT_FALSE(lookup_conductor("Unobtainium", &eta, &k));
  // Gold reflects red more than blue at normal incidence.
  ASSERT_TRUE(lookup_conductor("Au", &eta, &k));
  Rgb f = fresnel_conductor(1.0f, eta, k);
  EXPECT_GT(f.r, f.b);
}

TEST(BsdfTwoSided, BackMirrorsFront) {
  Bsdf b = make_bsdf(BsdfType::kRoughConductor, MicrofacetType::kGGX, 0.3f);
  Bsdf t = b;
  t.two_sided = true;
  Vec3f wo = direction_with_cos(0.6f), wi = direction_with_cos(0.4f, 2.0f);
  Vec3f wo_b(wo.x, wo.y, -wo.z), wi_b(wi.x, wi.y, -wi.z);
  EXPECT_EQ(bsdf_eval(b, kUv, wo_b, wi_b).r, 0.0f);  // one-sided: black from below
  EXPECT_FLOAT_EQ(bsdf_eval(t, kUv, wo_b, wi_b).g, bsdf_eval(t, kUv, wo, wi).g);
  EXPECT_FLOAT_EQ(bsdf_pdf(t, kUv, wo_b, wi_b), bsdf_pdf(t, kUv, wo, wi));
  BsdfSample s;
  ASSERT_TRUE(bsdf_sample(t, kUv, wo_b, 0.5f, Vec2f(0.3f, 0.6f), &s));
  EXPECT_LT(s.wi.z, 0.0f);
}

TEST(BsdfRoughness, ClassifiesLobes) {
  EXPECT_TRUE(std::isinf(make_bsdf(BsdfType::kDiffuse).roughness()));
  EXPECT_EQ(make_bsdf(BsdfType::kConductor).roughness(), 0.0f);
  EXPECT_EQ(make_bsdf(BsdfType::kDielectric).roughness(), 0.0f);
  EXPECT_FLOAT_EQ(make_bsdf(BsdfType::kRoughConductor, MicrofacetType::kGGX, 0.3f, 0.1f).roughness(), 0.1f);
  Bsdf p = make_bsdf(BsdfType::kPlastic);
  EXPECT_TRUE(std::isinf(bsdf_lobe_roughness(p, kLobeDiffuseReflection)));
  EXPECT_EQ(bsdf_lobe_roughness(p, kLobeDeltaReflection), 0.0f);
}

TEST(BsdfRoughPlastic, TablesMatchSmoothLimit) {
  // For a nearly smooth interface the tabulated transmittance is 1 - F(cos).
  Bsdf b = make_bsdf(BsdfType::kRoughPlastic, MicrofacetType::kBeckmann, 0.01f);
  float eta = b.int_ior / b.ext_ior;
  EXPECT_NEAR(b.rough_transmittance[63], 1.0f - fresnel_dielectric(1.0f, eta).f, 2e-3f);
  EXPECT_NEAR(b.rough_transmittance[32], 1.0f - fresnel_dielectric(32.0f / 63.0f, eta).f, 5e-3f);
  // Internal diffuse reflectance approaches the smooth Fdr_int (Mitsuba's table is a coarse mean).
  EXPECT_NEAR(b.rough_internal_reflectance, b.fdr_int, 0.03f);
}

}  // namespace gdvr::testing
