// The OIDN wrapper (core/denoise/oidn_denoiser.h), and with it the feature
// buffers' use. A build with OIDN denoises for real; a build without it
// registers the test of its refusal instead, so that no test passes by
// skipping what it cannot check.
#include "core/denoise/oidn_denoiser.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/render/feature_buffers.h"
#include "core/render/pt_integrator.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

constexpr float kLevel = 0.5f;

// A constant image of kLevel with white noise of relative amplitude 50 %.
Image noisy_constant(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Image img(w, h, 3);
  for (float& v : img.data()) v = kLevel * (1.0f + 0.5f * u(rng));
  return img;
}

Image constant(int w, int h, Rgb value) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set_rgb(x, y, value);
  return img;
}

double rms_error(const Image& img, float level) {
  double sum = 0;
  for (float v : img.data()) sum += double(v - level) * double(v - level);
  return std::sqrt(sum / double(img.data().size()));
}

#ifdef GDVR_HAVE_OIDN

TEST(OidnDenoiserTest, RejectsImagesThatDoNotMatch) {
  auto denoiser = OidnDenoiser::create();
  ASSERT_TRUE(denoiser.ok()) << denoiser.status().to_string();
  const Image color = noisy_constant(8, 8, 1);
  const Image narrow = constant(4, 8, Rgb(0.5f));
  DenoiseInputs in;
  in.color = &color;
  in.albedo = &narrow;
  EXPECT_EQ(denoiser.value()->denoise(in).status().code(), StatusCode::kInvalidArgument);
  in.albedo = nullptr;
  in.normal = &color;  // a normal without an albedo
  EXPECT_EQ(denoiser.value()->denoise(in).status().code(), StatusCode::kInvalidArgument);
}

TEST(OidnDenoiserTest, NoisyConstantImageComesBackNearTheConstant) {
  ASSERT_TRUE(OidnDenoiser::available());
  auto denoiser = OidnDenoiser::create(OidnDenoiserSettings{2});
  ASSERT_TRUE(denoiser.ok()) << denoiser.status().to_string();
  const int w = 64, h = 48;
  const Image color = noisy_constant(w, h, 7);
  const Image albedo = constant(w, h, Rgb(0.8f));
  const Image normal = constant(w, h, Rgb(0.0f, 0.0f, 1.0f));
  const double noisy_error = rms_error(color, kLevel);
  for (bool guided : {false, true}) {
    SCOPED_TRACE(guided ? "albedo and normal" : "colour only");
    DenoiseInputs in;
    in.color = &color;
    if (guided) {
      in.albedo = &albedo;
      in.normal = &normal;
    }
    auto out = denoiser.value()->denoise(in);
    ASSERT_TRUE(out.ok()) << out.status().to_string();
    ASSERT_EQ(out->width(), w);
    ASSERT_EQ(out->height(), h);
    double mean = 0;
    for (float v : out->data()) {
      ASSERT_TRUE(std::isfinite(v));
      mean += v;
    }
    mean /= double(out->data().size());
    EXPECT_NEAR(mean, kLevel, 0.05 * kLevel);
    EXPECT_LT(rms_error(out.value(), kLevel), 0.25 * noisy_error);
  }
  // The filter kept for one size is remade for another.
  const Image other = noisy_constant(32, 32, 9);
  DenoiseInputs in;
  in.color = &other;
  auto out = denoiser.value()->denoise(in);
  ASSERT_TRUE(out.ok()) << out.status().to_string();
  EXPECT_EQ(out->width(), 32);
}

// The whole baseline on the Cornell box at 4 spp: the path tracer's image,
// the feature buffers, OIDN. Closer to a 256-spp reference than the image it
// was given, by a wide margin (the point of the baseline).
TEST(OidnDenoiserTest, GuidedDenoiseOfAFewSamplesPerPixelComesCloserToTheReference) {
  constexpr int kSize = 64;
  auto ts = test::load_test_scene("cbox", kSize, kSize);
  ASSERT_TRUE(ts);
  FrameRenderSettings rs = ts->render;
  rs.threads = 2;
  rs.seed = 3;
  rs.spp = 256;
  auto reference = render_frame_pt(*ts->scene, rs, 0, {});
  ASSERT_TRUE(reference.ok()) << reference.status().to_string();
  rs.seed = 4;
  rs.spp = 4;
  auto noisy = render_frame_pt(*ts->scene, rs, 0, {});
  ASSERT_TRUE(noisy.ok()) << noisy.status().to_string();
  auto features = render_feature_buffers(*ts->scene, rs, feature_buffer_settings_for(rs.spp), nullptr);
  ASSERT_TRUE(features.ok()) << features.status().to_string();

  auto denoiser = OidnDenoiser::create(OidnDenoiserSettings{2});
  ASSERT_TRUE(denoiser.ok()) << denoiser.status().to_string();
  DenoiseInputs in;
  in.color = &noisy->color;
  in.albedo = &features->albedo;
  in.normal = &features->normal;
  auto denoised = denoiser.value()->denoise(in);
  ASSERT_TRUE(denoised.ok()) << denoised.status().to_string();
  const double before = test::rel_mse(noisy->color, reference->color);
  const double after = test::rel_mse(denoised.value(), reference->color);
  EXPECT_LT(after, 0.5 * before) << "relMSE " << before << " -> " << after;
}

#else

TEST(OidnDenoiserTest, BuildWithoutOidnSaysSo) {
  EXPECT_FALSE(OidnDenoiser::available());
  auto denoiser = OidnDenoiser::create();
  ASSERT_FALSE(denoiser.ok());
  EXPECT_EQ(denoiser.status().code(), StatusCode::kUnimplemented);
  EXPECT_NE(denoiser.status().message().find("built without Intel Open Image Denoise"), std::string::npos)
      << denoiser.status().message();
  EXPECT_NE(denoiser.status().message().find("install-deps.sh"), std::string::npos);
}

#endif

}  // namespace
}  // namespace gdvr
