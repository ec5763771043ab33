// Stiff cases with an analytic or structural answer: the closed furnace at
// max_depth 1000, scale invariance at 1e-4 and 1e5, the mesh loader on
// degenerate / non-finite data, a frame where every cached-path shift fails.
#include <gtest/gtest.h>

#include <ostream>

#include "core/render/perspective_camera.h"
#include "core/render/path_tracer.h"
#include "tests/core/stiff/stiff_test_util.h"

namespace gdvr::stiff {
namespace {

const StiffCase& find_case(const std::string& name) {
  static const std::vector<StiffCase> cases = stiff_cases();
  for (const StiffCase& c : cases)
    if (name == c.name) return c;
  ADD_FAILURE() << "no case " << name;
  return cases[0];
}

// ---- Very long paths: closed furnace, albedo 0.99, max_depth 1000 ----

class StiffFurnaceTest : public ::testing::TestWithParam<Integ> {};

TEST_P(StiffFurnaceTest, MatchesLeOverOneMinusRho) {
  const StiffCase& c = find_case("furnace_depth1000");
  const double rho = 0.99, expected = (1.0 - std::pow(rho, 1000)) / (1.0 - rho);  // Le = 1
  auto out = run(make_job(c, GetParam(), 64, 3));
  ASSERT_FALSE(out.empty());
  for (const FrameOutput& f : out) {
    EXPECT_EQ(non_finite_layers(f), "");
    const Image& img = f.image.find("")->image;
    // Pixels are independent estimates of the same value: standard error from their spread.
    double sum = 0, sum2 = 0;
    for (float v : img.data()) sum += v, sum2 += double(v) * v;
    const double n = double(img.data().size()), mean = sum / n;
    const double se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
    std::printf("[ furnace ] %s frame %d: mean %.4f (expected %.4f), pixel spread se %.4f\n", integ_name(GetParam()),
                f.frame, mean, expected, se);
    if (GetParam() == Integ::kPt) {
      EXPECT_NEAR(mean, expected, 5 * se + 1e-3 * expected);
    } else {
      // A reconstruction correlates the pixels, so their spread understates the
      // error of the mean; the primal (plain PT estimate) must still match, and
      // the reconstructed image within 2 %.
      const Image& primal = f.image.find("primal")->image;
      const Image& direct = f.image.find("direct")->image;
      double psum = 0, psum2 = 0;
      for (size_t k = 0; k < primal.data().size(); ++k) {
        double v = double(primal.data()[k]) + direct.data()[k];
        psum += v, psum2 += v * v;
      }
      const double pmean = psum / n, pse = std::sqrt(std::max(0.0, psum2 / n - pmean * pmean) / n);
      EXPECT_NEAR(pmean, expected, 5 * pse + 1e-3 * expected);
      EXPECT_NEAR(mean, expected, 0.02 * expected);
    }
  }
}

// Truncated series Le (1 - rho^k) / (1 - rho) for short max_depth k (pt).
TEST(StiffFurnaceTest, TruncatedSeriesForShortPaths) {
  const StiffCase& base = find_case("furnace_depth1000");
  for (auto [albedo, depth] : {std::pair<double, int>{0.5, 2}, {0.5, 3}, {0.9, 10}, {0.99, 50}, {0.99, 200}}) {
    StiffCase c = base;
    c.params = {{"albedo", std::to_string(albedo)}, {"max_depth", std::to_string(depth)}};
    auto out = run(make_job(c, Integ::kPt, 64, 3));
    ASSERT_EQ(out.size(), 1u);
    const Image& img = out[0].image.find("")->image;
    double sum = 0, sum2 = 0;
    for (float v : img.data()) sum += v, sum2 += double(v) * v;
    const double n = double(img.data().size()), mean = sum / n;
    const double se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
    const double expected = (1.0 - std::pow(albedo, depth)) / (1.0 - albedo);
    std::printf("[ furnace ] albedo %.2f max_depth %d: mean %.4f expected %.4f se %.4f\n", albedo, depth, mean,
                expected, se);
    EXPECT_NEAR(mean, expected, 5 * se + 1e-3 * expected) << "albedo " << albedo << " max_depth " << depth;
  }
}

// A furnace of albedo 1 with max_depth -1 loses no energy, so Russian
// roulette never ends a path (survival min(throughput, 1) = 1): without the
// depth limit the render never finished. With it every path has
// kUnboundedDepthLimit segments, each seeing Le = 1.
TEST(StiffFurnaceTest, LosslessUnboundedPathsEndAtTheDepthLimit) {
  StiffCase c = find_case("furnace_depth1000");
  c.params = {{"albedo", "1"}, {"max_depth", "-1"}};
  c.res = 2;
  for (Integ integ : {Integ::kPt, Integ::kGptReconnect}) {
    auto out = run(make_job(c, integ, 1, 3));
    ASSERT_EQ(out.size(), 1u) << integ_name(integ);
    EXPECT_EQ(non_finite_layers(out[0]), "");
    const Image& img = out[0].image.find(integ == Integ::kPt ? "" : "primal")->image;
    const Image* direct = integ == Integ::kPt ? nullptr : &out[0].image.find("direct")->image;
    double sum = 0;
    for (size_t k = 0; k < img.data().size(); ++k) sum += img.data()[k] + (direct ? direct->data()[k] : 0.0f);
    const double mean = sum / double(img.data().size());
    std::printf("[ furnace ] %s albedo 1, unbounded: mean %.1f, limit %d\n", integ_name(integ), mean,
                kUnboundedDepthLimit);
    // Each bounce's expected contribution is Le (emission hit and emitter
    // sample combined by MIS); 4 pixels x 3 channels x 65536 bounces of
    // independent MIS noise average out to well under 1 %.
    EXPECT_NEAR(mean, double(kUnboundedDepthLimit), 0.02 * kUnboundedDepthLimit) << integ_name(integ);
  }
}

INSTANTIATE_TEST_SUITE_P(Stiff, StiffFurnaceTest, ::testing::ValuesIn(all_integrators()),
                         [](const auto& info) { return std::string(integ_name(info.param)); });

// ---- Scale invariance: the room at 1e-4 and 1e5 renders the scale-1 image ----

struct ScaleParam {
  const char* scale;
  const char* near;
  const char* far;
  Integ integ;
};
// Readable names in ctest output instead of the parameter's bytes.
void PrintTo(const ScaleParam& p, std::ostream* os) { *os << p.scale << "/" << integ_name(p.integ); }

class StiffScaleTest : public ::testing::TestWithParam<ScaleParam> {};

TEST_P(StiffScaleTest, SameImageAsScaleOne) {
  StiffCase unit{"scale_1", "scaled.xml", {{"s", "1"}, {"near", "0.001"}}, 16, 32, 1024};
  StiffCase scaled = unit;
  scaled.params = {{"s", GetParam().scale}, {"near", GetParam().near}, {"far", GetParam().far}};
  const Image& ref = pt_reference(unit, false)[0];
  // Same seed: the same random numbers drive both scenes, so the images agree
  // far more closely than either agrees with the reference.
  auto a = run(make_job(unit, GetParam().integ, 32, 21));
  auto b = run(make_job(scaled, GetParam().integ, 32, 21));
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(non_finite_layers(b[0]), "");
  const Image& ia = a[0].image.find("")->image;
  const Image& ib = b[0].image.find("")->image;
  const double e_unit = rel_mse(ia, ref), e_scaled = rel_mse(ib, ref), e_pair = rel_mse(ib, ia);
  std::printf("[ scale ] s=%s %s: relMSE vs ref %.3g (scale 1: %.3g), scaled vs scale 1 %.3g; means %.4f / %.4f\n",
              GetParam().scale, integ_name(GetParam().integ), e_scaled, e_unit, e_pair, mean_of(ib), mean_of(ia));
  EXPECT_LT(e_scaled, 1.5 * e_unit);
  EXPECT_LT(e_pair, 0.5 * e_unit);
  EXPECT_NEAR(mean_of(ib), mean_of(ia), 0.02 * mean_of(ia));
}

std::vector<ScaleParam> scale_params() {
  std::vector<ScaleParam> v;
  for (Integ i : {Integ::kPt, Integ::kGptReplay, Integ::kGptReconnect, Integ::kGptHybrid}) {
    v.push_back({"1e-4", "1e-7", "1", i});
    v.push_back({"1e5", "100", "1e9", i});
  }
  return v;
}

INSTANTIATE_TEST_SUITE_P(Stiff, StiffScaleTest, ::testing::ValuesIn(scale_params()), [](const auto& info) {
  return std::string(info.param.scale[1] == 'e' && info.param.scale[2] == '-' ? "1em4" : "1e5") + "_" +
         integ_name(info.param.integ);
});

// ---- Mesh loader: repair what can be repaired, reject what cannot ----

TEST(StiffLoaderTest, DegenerateTrianglesAndNonFiniteNormalsAndUvsAreRepairedWithAWarning) {
  auto desc = load_case(find_case("degenerate_mesh"));
  ASSERT_TRUE(desc.ok()) << desc.status().to_string();
  std::string warnings;
  for (const std::string& w : desc->warnings) warnings += w + "\n";
  EXPECT_NE(warnings.find("degenerate.obj"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("dropped 3 degenerate triangle(s)"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("recomputed normals"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("non-finite uv"), std::string::npos) << warnings;
  const Shape* platform = nullptr;
  for (const Shape& s : desc->shapes)
    if (s.id == "platform") platform = &s;
  ASSERT_NE(platform, nullptr);
  ASSERT_TRUE(platform->mesh);
  EXPECT_EQ(platform->mesh->triangle_count(), 2u);
  for (const Vec3f& n : platform->mesh->normals) {
    EXPECT_TRUE(is_finite(n));
    EXPECT_NEAR(length(n), 1.0f, 1e-5f);
  }
  for (const Vec2f& uv : platform->mesh->uvs) EXPECT_TRUE(std::isfinite(uv.x) && std::isfinite(uv.y));
}

TEST(StiffLoaderTest, NonFinitePositionIsRejectedNamingTheFileAndVertex) {
  LoadOptions lo;
  auto desc = load_mitsuba_scene(stiff_dir() + "/bad_position.xml", lo);
  ASSERT_FALSE(desc.ok());
  const std::string msg = desc.status().to_string();
  EXPECT_NE(msg.find("bad_position"), std::string::npos) << msg;
  EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
  EXPECT_NE(msg.find("vertex"), std::string::npos) << msg;
}

// ---- A frame where every cached-path shift fails ----

class StiffAllShiftsFailTest : public ::testing::TestWithParam<Integ> {};

TEST_P(StiffAllShiftsFailTest, FailureRateIsOneOnEveryTileAndTheImageIsStillRight) {
  const StiffCase& c = find_case("all_shifts_fail");
  auto out = run(make_job(c, GetParam(), 64, 5));
  ASSERT_EQ(out.size(), 1u);
  const FrameOutput& f = out[0];
  EXPECT_EQ(non_finite_layers(f), "");
  const Image& primal = f.image.find("primal")->image;
  const Image& rate = f.image.find("shift_failure_rate")->image;
  const Image& fin = f.image.find("")->image;
  int tiles = 0, wrong = 0;
  double worst = 0;
  Image analytic(c.res, c.res, 3);
  for (int y = 0; y < c.res; ++y)
    for (int x = 0; x < c.res; ++x) {
      // Tile pixels reflect albedo 0.5 x sky 1 (indirect); sky pixels are direct only.
      const bool tile = primal.at(x, y, 0) > 0.25f;
      tiles += tile;
      const float expected_rate = GetParam() == Integ::kGptReplay ? 0.0f : 1.0f;
      if (tile && rate.at(x, y, 0) != expected_rate) ++wrong;
      for (int ch = 0; ch < 3; ++ch) {
        analytic.at(x, y, ch) = tile ? 0.5f : 1.0f;
        worst = std::max(worst, std::abs(double(fin.at(x, y, ch)) - analytic.at(x, y, ch)));
      }
    }
  const double e = rel_mse(fin, analytic);
  std::printf("[ all fail ] %s: %d tile pixels, %d with an unexpected failure rate, relMSE vs analytic %.3g, worst "
              "|final - analytic| %.4f\n",
              integ_name(GetParam()), tiles, wrong, e, worst);
  EXPECT_EQ(tiles, c.res * c.res / 2);
  EXPECT_EQ(wrong, 0);
  EXPECT_LT(e, 0.01);
  EXPECT_LT(worst, 0.5);
}

INSTANTIATE_TEST_SUITE_P(Stiff, StiffAllShiftsFailTest,
                         ::testing::Values(Integ::kGptReplay, Integ::kGptReconnect, Integ::kGptHybrid),
                         [](const auto& info) { return std::string(integ_name(info.param)); });

}  // namespace
}  // namespace gdvr::stiff

namespace gdvr::stiff {
namespace {

// ---- A tiny, very bright sphere light: analytic direct illumination ----
// 1 - cos(alpha) = 2e-6 is a few float ulps; the cone pdf must not be formed
// from a float cos(alpha), or the irradiance is off by several percent, and
// the sampled point must not come from intersecting the sampled ray with the
// sphere in float (points land on the back side: whole samples go black).
class StiffTinyLightTest : public ::testing::TestWithParam<Integ> {};

TEST_P(StiffTinyLightTest, DirectIrradianceMatchesTheSphereFormula) {
  StiffCase c{"tiny_light_direct", "tiny_light_direct.xml", {}, 16, 16, 16};
  auto desc = load_case(c);
  ASSERT_TRUE(desc.ok()) << desc.status().to_string();
  PerspectiveCamera camera(desc->camera, c.res, c.res);
  auto out = run(make_job(c, GetParam(), 16, 8));
  ASSERT_FALSE(out.empty());
  const FrameOutput& f = out[0];
  EXPECT_EQ(non_finite_layers(f), "");
  const Image& img = f.image.find("")->image;
  double worst = 0, mean_ratio = 0;
  for (int y = 0; y < c.res; ++y)
    for (int x = 0; x < c.res; ++x) {
      // Mean of 2 / d^3 over the pixel (3 x 3 sub-pixel points on the plane y = 0).
      double expected = 0;
      for (int sy = 0; sy < 3; ++sy)
        for (int sx = 0; sx < 3; ++sx) {
          Ray r = camera.generate_ray({float(x) + (sx + 0.5f) / 3, float(y) + (sy + 0.5f) / 3});
          double t = -double(r.o.y) / r.d.y;
          double px = r.o.x + t * r.d.x, pz = r.o.z + t * r.d.z;
          double d2 = px * px + pz * pz + 1.0;
          expected += 2.0 / (d2 * std::sqrt(d2)) / 9.0;
        }
      const double ratio = img.at(x, y, 1) / expected;
      mean_ratio += ratio / double(c.res * c.res);
      worst = std::max(worst, std::abs(ratio - 1.0));
    }
  std::printf("[ tiny light ] %s: mean image/analytic %.5f, worst pixel %.4f\n", integ_name(GetParam()), mean_ratio,
              worst);
  EXPECT_NEAR(mean_ratio, 1.0, 1e-3);
  EXPECT_LT(worst, 0.005);
}

INSTANTIATE_TEST_SUITE_P(Stiff, StiffTinyLightTest, ::testing::ValuesIn(all_integrators()),
                         [](const auto& info) { return std::string(integ_name(info.param)); });

}  // namespace
}  // namespace gdvr::stiff
