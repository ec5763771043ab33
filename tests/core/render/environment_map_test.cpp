// The environment map's lookup against Mitsuba 3.9.1's `envmap` (values read
// back with Emitter.eval), and its importance sampling against its own pdf.
#include <gtest/gtest.h>

#include <cmath>

#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/render/frame_scene.h"

namespace gdvr {
namespace {

// The direction of lat-long position (u, v) in the map's frame (Mitsuba's
// convention: u = atan2(x, -z) / 2 pi, v = acos(y) / pi).
Vec3f direction_of(double u, double v) {
  const double theta = v * M_PI, phi = u * 2 * M_PI;
  return Vec3f(float(std::sin(phi) * std::sin(theta)), float(std::cos(theta)), float(-std::cos(phi) * std::sin(theta)));
}

std::unique_ptr<FrameScene> environment_scene(std::shared_ptr<Image> image) {
  Scene scene;
  Emitter env;
  env.type = EmitterType::kEnvmap;
  env.envmap = std::move(image);
  scene.emitters.push_back(env);
  auto fs = FrameScene::create(scene, {});
  EXPECT_TRUE(fs.ok()) << fs.status().to_string();
  return fs.ok() ? std::move(fs.value()) : nullptr;
}

// An 8 x 4 map whose texel (x, y) is (x + 1, y + 1, 10 y + x + 1).
// Mitsuba 3 puts texel centres at u = (x + 1/2) / 8, wrapping between the
// last and the first column, and rows at v = y / 3.
TEST(EnvironmentMapTest, LookupMatchesMitsubasTexelCentres) {
  auto image = std::make_shared<Image>(8, 4, 3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x) image->set_rgb(x, y, Rgb(float(x + 1), float(y + 1), float(10 * y + x + 1)));
  auto fs = environment_scene(image);
  ASSERT_TRUE(fs);
  struct Case {
    double u, v;
    Rgb expected;  // Mitsuba 3.9.1
  } cases[] = {
      {0.0625, 0.5, Rgb(1.0f, 2.5f, 16.0f)},  {0.125, 0.5, Rgb(1.5f, 2.5f, 16.5f)},
      {0.0, 0.5, Rgb(4.5f, 2.5f, 19.5f)},     {0.9375, 0.5, Rgb(8.0f, 2.5f, 23.0f)},
      {0.3, 0.125, Rgb(2.9f, 1.375f, 6.65f)}, {0.3, 0.875, Rgb(2.9f, 3.625f, 29.15f)},
  };
  for (const Case& c : cases) {
    const Rgb got = fs->eval_environment(direction_of(c.u, c.v));
    EXPECT_NEAR(got.r, c.expected.r, 1e-4f) << "u=" << c.u << " v=" << c.v;
    EXPECT_NEAR(got.g, c.expected.g, 1e-4f) << "u=" << c.u << " v=" << c.v;
    EXPECT_NEAR(got.b, c.expected.b, 1e-4f) << "u=" << c.u << " v=" << c.v;
  }
}

// Emitter sampling must see all of the map: E[L / pdf] over its samples
// equals the integral of L over the sphere (by uniform sampling), and the
// pdf it reports is the one pdf_environment_direction gives the direction.
// The map is black but for a few bright texels next to black ones, where a
// pdf taken from one point per cell can be zero while the bilinear lookup is
// not.
TEST(EnvironmentMapTest, SamplingIsUnbiasedAndPdfsAgree) {
  auto image = std::make_shared<Image>(16, 8, 3);
  image->set_rgb(3, 2, Rgb(50.0f));
  image->set_rgb(4, 2, Rgb(20.0f, 5.0f, 1.0f));
  image->set_rgb(15, 5, Rgb(8.0f));
  image->set_rgb(0, 7, Rgb(3.0f));
  auto fs = environment_scene(image);
  ASSERT_TRUE(fs);
  SurfaceInteraction origin;
  Pcg32 rng;
  rng.seed(3, 9);
  const int n = 400000;
  double sampled = 0, sampled2 = 0, uniform = 0, uniform2 = 0;
  int pdf_mismatches = 0;
  for (int i = 0; i < n; ++i) {
    const float u_select = rng.next_float();
    const Vec2f u{rng.next_float(), rng.next_float()};
    const EmitterSample es = fs->sample_emitter_direction(origin, u_select, u);
    const double v = es.weight.r;
    sampled += v;
    sampled2 += v * v;
    if (es.pdf > 0) {
      const float pdf = fs->pdf_environment_direction(es.d);
      if (std::abs(pdf - es.pdf) > 1e-3f * es.pdf) ++pdf_mismatches;
    }
    const Vec3f d = square_to_uniform_sphere({rng.next_float(), rng.next_float()});
    const double l = fs->eval_environment(d).r * 4 * M_PI;
    uniform += l;
    uniform2 += l * l;
  }
  const double m_s = sampled / n, m_u = uniform / n;
  const double e_s = std::sqrt((sampled2 / n - m_s * m_s) / n), e_u = std::sqrt((uniform2 / n - m_u * m_u) / n);
  EXPECT_NEAR(m_s, m_u, 4 * std::hypot(e_s, e_u)) << "emitter sampling " << m_s << " uniform " << m_u;
  EXPECT_LT(e_s, e_u);  // and it is importance sampling
  EXPECT_LE(pdf_mismatches, n / 10000);
}

}  // namespace
}  // namespace gdvr
