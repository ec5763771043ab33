#include "core/io/color_transform.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

namespace gdvr {
namespace {

const std::string kShippedConfig = std::string(GDVR_SOURCE_DIR) + "/data/ocio/config.ocio";

ColorTransform make(const std::string& view, bool clamp = true) {
  ColorTransformOptions o;
  o.config_path = kShippedConfig;
  o.view = view;
  o.clamp_output = clamp;
  Expected<ColorTransform> t = ColorTransform::create(o);
  EXPECT_TRUE(t.ok()) << t.status().to_string();
  return std::move(t).value();
}

Image solid(float r, float g, float b, int w = 3, int h = 2) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set_rgb(x, y, {r, g, b});
  return img;
}

float srgb_encode(float v) {
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

TEST(OcioConfig, ShippedConfigLoadsAndListsViews) {
  Expected<std::vector<std::string>> displays = ColorTransform::list_displays(kShippedConfig);
  ASSERT_TRUE(displays.ok()) << displays.status().to_string();
  ASSERT_EQ(displays.value(), std::vector<std::string>{"sRGB - Display"});
  Expected<std::vector<std::string>> views = ColorTransform::list_views(kShippedConfig, "sRGB - Display");
  ASSERT_TRUE(views.ok()) << views.status().to_string();
  EXPECT_EQ(views.value(), (std::vector<std::string>{"ACES 1.0 - SDR Video", "Un-tone-mapped", "Raw"}));
}

TEST(OcioConfig, ResolvePrefersEnvironment) {
  const char* old = std::getenv("OCIO");
  const std::string saved = old ? old : "";
  ::unsetenv("OCIO");
  EXPECT_EQ(resolve_ocio_config_path("shipped.ocio"), "shipped.ocio");
  ::setenv("OCIO", "/studio/config.ocio", 1);
  EXPECT_EQ(resolve_ocio_config_path("shipped.ocio"), "/studio/config.ocio");
  if (old) ::setenv("OCIO", saved.c_str(), 1); else ::unsetenv("OCIO");
}

TEST(ColorTransform, AcesSdrVideoMidGreyAndBlack) {
  const ColorTransform t = make("ACES 1.0 - SDR Video");
  Expected<Image> grey = t.apply(solid(0.18f, 0.18f, 0.18f));
  ASSERT_TRUE(grey.ok()) << grey.status().to_string();
  ASSERT_EQ(grey->channels(), 3);
  const Rgb g = grey->rgb(1, 1);
  // ACES 1.0 SDR maps scene 0.18 to ~10 nits of 100, ~0.35-0.40 encoded.
  EXPECT_GT(g.r, 0.3f);
  EXPECT_LT(g.r, 0.5f);
  // Neutral stays neutral (D60/D65 adaptation must cancel).
  EXPECT_NEAR(g.r, g.g, 2e-3f);
  EXPECT_NEAR(g.b, g.g, 2e-3f);

  Expected<Image> black = t.apply(solid(0, 0, 0));
  ASSERT_TRUE(black.ok());
  for (float v : black->data()) EXPECT_LT(v, 0.01f);
}

TEST(ColorTransform, OutputStaysInUnitRange) {
  const ColorTransform t = make("ACES 1.0 - SDR Video");
  Image img(6, 1, 3);
  const Rgb inputs[] = {{1e4f, 1e4f, 1e4f}, {50, 0, 0}, {0, 0, 20}, {-1, 0.5f, 2}, {0.9f, 0.9f, 0.0f},
                        {NAN, INFINITY, 1}};
  for (int x = 0; x < 6; ++x) img.set_rgb(x, 0, inputs[x]);
  Expected<Image> out = t.apply(img);
  ASSERT_TRUE(out.ok());
  for (float v : out->data()) {
    EXPECT_TRUE(std::isfinite(v));
    EXPECT_GE(v, 0.0f);
    EXPECT_LE(v, 1.0f);
  }
  EXPECT_GT(out->at(0, 0, 0), 0.95f);  // very bright saturates to white
}

TEST(ColorTransform, UntoneMappedIsPlainSrgbEncoding) {
  // Known answer: without tone mapping, linear Rec.709 -> ACES -> XYZ -> sRGB
  // must collapse to the sRGB curve, which checks every matrix in the chain.
  const ColorTransform t = make("Un-tone-mapped");
  Image img(4, 1, 3);
  img.set_rgb(0, 0, {0.18f, 0.18f, 0.18f});
  img.set_rgb(1, 0, {0.5f, 0.2f, 0.05f});
  img.set_rgb(2, 0, {0.01f, 0.7f, 0.3f});
  img.set_rgb(3, 0, {1.0f, 1.0f, 1.0f});
  Expected<Image> out = t.apply(img);
  ASSERT_TRUE(out.ok());
  for (int x = 0; x < 4; ++x)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(out->at(x, 0, c), srgb_encode(img.at(x, 0, c)), 2e-3f) << x << "," << c;
}

TEST(ColorTransform, RawViewPassesThrough) {
  const ColorTransform t = make("Raw");
  Expected<Image> out = t.apply(solid(0.25f, 0.5f, 0.75f));
  ASSERT_TRUE(out.ok());
  EXPECT_FLOAT_EQ(out->at(0, 0, 0), 0.25f);
  EXPECT_FLOAT_EQ(out->at(0, 0, 2), 0.75f);
}

TEST(ColorTransform, ExtraChannelsIgnoredAndLargeImagesParallel) {
  const ColorTransform t = make("ACES 1.0 - SDR Video");
  Image img(37, 101, 4);  // odd size spans several parallel row bands
  for (size_t i = 0; i < img.pixel_count(); ++i) {
    img.data()[i * 4 + 0] = img.data()[i * 4 + 1] = img.data()[i * 4 + 2] = 0.18f;
    img.data()[i * 4 + 3] = 123.0f;
  }
  Expected<Image> out = t.apply(img);
  ASSERT_TRUE(out.ok());
  ASSERT_EQ(out->channels(), 3);
  const float ref = out->at(0, 0, 0);
  for (float v : out->data()) EXPECT_FLOAT_EQ(v, ref);
}

TEST(ColorTransform, UnknownViewListsAvailable) {
  ColorTransformOptions o;
  o.config_path = kShippedConfig;
  o.view = "Filmic";
  Expected<ColorTransform> t = ColorTransform::create(o);
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidArgument);
  const std::string& m = t.status().message();
  EXPECT_NE(m.find("'Filmic'"), std::string::npos) << m;
  EXPECT_NE(m.find("ACES 1.0 - SDR Video"), std::string::npos) << m;
  EXPECT_NE(m.find("Un-tone-mapped"), std::string::npos) << m;
}

TEST(ColorTransform, UnknownDisplayAndColorspaceAndConfig) {
  ColorTransformOptions o;
  o.config_path = kShippedConfig;
  o.display = "P3-D65 - Display";
  Expected<ColorTransform> t = ColorTransform::create(o);
  ASSERT_FALSE(t.ok());
  EXPECT_NE(t.status().message().find("sRGB - Display"), std::string::npos) << t.status().message();

  o = ColorTransformOptions{};
  o.config_path = kShippedConfig;
  o.input_colorspace = "Linear P3";
  EXPECT_FALSE(ColorTransform::create(o).ok());

  o = ColorTransformOptions{};
  o.config_path = "/nonexistent/config.ocio";
  t = ColorTransform::create(o);
  ASSERT_FALSE(t.ok());
  EXPECT_NE(t.status().message().find("/nonexistent/config.ocio"), std::string::npos);

  EXPECT_FALSE(make("Raw").apply(Image(2, 2, 1)).ok());
}

}  // namespace
}  // namespace gdvr
