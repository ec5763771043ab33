// Texture evaluation against Mitsuba 3's conventions.
#include <gtest/gtest.h>

#include <memory>

#include "core/texture/texture.h"

namespace gdvr {
namespace {

Texture checkerboard() {
  Texture t;
  t.type = TextureType::kCheckerboard;
  t.color0 = Rgb(0.4f);
  t.color1 = Rgb(0.2f);
  return t;
}

// 2x2 RGB image: row 0 = (0, 1), row 1 = (2, 3) in the red channel.
Texture bitmap_2x2() {
  auto img = std::make_shared<Image>(2, 2, 3);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) img->set_rgb(x, y, Rgb(float(y * 2 + x), 10.0f, 0.0f));
  Texture t;
  t.type = TextureType::kBitmap;
  t.bitmap = img;
  return t;
}

TEST(TextureCheckerboard, PatternAtKnownUvs) {
  Texture t = checkerboard();
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.25f, 0.25f)).r, 0.4f);  // both halves low: color0
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.75f, 0.25f)).r, 0.2f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.25f, 0.75f)).r, 0.2f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.75f, 0.75f)).r, 0.4f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(1.25f, -0.75f)).r, 0.4f);  // periodic, floor-based
  EXPECT_FLOAT_EQ(t.mean().g, 0.3f);
}

TEST(TextureCheckerboard, ToUvScale) {
  Texture t = checkerboard();
  t.to_uv.a = 8;  // matpreview: <scale x="8" y="8"/>
  t.to_uv.e = 8;
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.03f, 0.03f)).r, 0.4f);   // (0.24, 0.24)
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.09f, 0.03f)).r, 0.2f);   // (0.72, 0.24)
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.155f, 0.03f)).r, 0.4f);  // (1.24, 0.24)
}

TEST(TextureUvTransform, Apply) {
  UvTransform m;
  EXPECT_TRUE(m.is_identity());
  m.a = 2; m.b = 1; m.c = 0.5f; m.d = 0; m.e = 3; m.f = -1;
  Vec2f r = m.apply(Vec2f(1, 2));
  EXPECT_FLOAT_EQ(r.x, 4.5f);
  EXPECT_FLOAT_EQ(r.y, 5.0f);
  EXPECT_FALSE(m.is_identity());
}

TEST(TextureBitmap, TexelCentresAndBilinear) {
  Texture t = bitmap_2x2();
  // Texel (x, y) has its centre at uv = ((x + 0.5) / w, (y + 0.5) / h); v = 0 is row 0.
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.25f, 0.25f)).r, 0.0f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.75f, 0.25f)).r, 1.0f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.25f, 0.75f)).r, 2.0f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.75f, 0.75f)).r, 3.0f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.5f, 0.5f)).r, 1.5f);   // average of all four
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.5f, 0.25f)).r, 0.5f);  // halfway along row 0
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.5f, 0.5f)).g, 10.0f);
}

TEST(TextureBitmap, RepeatWrap) {
  Texture t = bitmap_2x2();
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.0f, 0.0f)).r, 1.5f);  // corner blends the wrapped neighbours
  EXPECT_FLOAT_EQ(t.eval(Vec2f(1.25f, 0.25f)).r, 0.0f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(-0.25f, -0.25f)).r, 3.0f);
  EXPECT_FLOAT_EQ(t.eval(Vec2f(0.0f, 0.25f)).r, 0.5f);  // blends texel 1 (wrapped) and texel 0
}

TEST(TextureBitmap, MeanAndConstant) {
  Texture t = bitmap_2x2();
  EXPECT_FLOAT_EQ(t.mean().r, 1.5f);
  Texture c = Texture::constant(Rgb(0.1f, 0.2f, 0.3f));
  EXPECT_FLOAT_EQ(c.eval(Vec2f(7, 3)).b, 0.3f);
  EXPECT_FLOAT_EQ(c.mean().g, 0.2f);
}

// Nearest and bilinear lookups under each wrap mode, against Mitsuba 3.9.1's
// `bitmap` (raw, evaluated at these uvs) on a 4 x 2 image whose texel (x, y)
// is (x + 1, y + 1, 10 y + x + 1). gdvr rendered nearest as bilinear and
// mirror/clamp as repeat before: a generated scene's nearest-filtered floor
// was 3 % off Mitsuba.
TEST(TextureBitmap, FilterAndWrapModesMatchMitsuba) {
  auto img = std::make_shared<Image>(4, 2, 3);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) img->set_rgb(x, y, Rgb(float(x + 1), float(y + 1), float(10 * y + x + 1)));
  const Vec2f uvs[6] = {{0.1f, 0.2f}, {0.9f, 0.8f}, {-0.3f, 0.6f}, {1.37f, -0.2f}, {2.6f, 1.7f}, {0.55f, 0.5f}};
  struct Case {
    TextureFilter filter;
    TextureWrap wrap;
    Rgb expected[6];
  } cases[] = {
      {TextureFilter::kNearest, TextureWrap::kRepeat, {{1, 1, 1}, {4, 2, 14}, {3, 2, 13}, {2, 2, 12}, {3, 2, 13}, {3, 2, 13}}},
      {TextureFilter::kNearest, TextureWrap::kMirror, {{1, 1, 1}, {4, 2, 14}, {2, 2, 12}, {3, 1, 3}, {3, 1, 3}, {3, 2, 13}}},
      {TextureFilter::kNearest, TextureWrap::kClamp, {{1, 1, 1}, {4, 2, 14}, {1, 2, 11}, {4, 1, 4}, {4, 2, 14}, {3, 2, 13}}},
      {TextureFilter::kBilinear, TextureWrap::kRepeat,
       {{1.3f, 1.1f, 2.3f}, {3.7f, 1.9f, 12.7f}, {3.3f, 1.7f, 10.3f}, {1.98f, 1.9f, 10.98f}, {2.9f, 1.9f, 11.9f},
        {2.7f, 1.5f, 7.7f}}},
      {TextureFilter::kBilinear, TextureWrap::kMirror,
       {{1, 1, 1}, {4, 2, 14}, {1.7f, 1.7f, 8.7f}, {3.02f, 1, 3.02f}, {2.9f, 1.1f, 3.9f}, {2.7f, 1.5f, 7.7f}}},
      {TextureFilter::kBilinear, TextureWrap::kClamp,
       {{1, 1, 1}, {4, 2, 14}, {1, 1.7f, 8}, {4, 1, 4}, {4, 2, 14}, {2.7f, 1.5f, 7.7f}}},
  };
  for (const Case& c : cases) {
    Texture t;
    t.type = TextureType::kBitmap;
    t.bitmap = img;
    t.filter = c.filter;
    t.wrap = c.wrap;
    for (int i = 0; i < 6; ++i) {
      const Rgb got = t.eval(uvs[i]);
      const std::string what = "filter " + std::to_string(int(c.filter)) + " wrap " + std::to_string(int(c.wrap)) +
                               " uv " + std::to_string(i);
      EXPECT_NEAR(got.r, c.expected[i].r, 1e-4f) << what;
      EXPECT_NEAR(got.g, c.expected[i].g, 1e-4f) << what;
      EXPECT_NEAR(got.b, c.expected[i].b, 1e-4f) << what;
    }
  }
}

}  // namespace
}  // namespace gdvr
