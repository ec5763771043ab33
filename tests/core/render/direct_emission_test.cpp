// The stratified, edge-adaptive pass for emitters seen directly from the
// camera (core/render/direct_emission.h): unbiased against the path tracer's
// own first-hit emission, less noisy than the path samples it replaces,
// deterministic, and black with hide_emitters.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/render/direct_emission.h"
#include "core/scene/mitsuba_loader.h"
#include "tests/core/gradient/gpt_test_util.h"
#include "tests/core/stiff/stiff_test_util.h"

namespace gdvr {
namespace {

using test::load_test_scene;

constexpr int kSize = 24;

Image direct_pass(const test::TestScene& ts, DirectEmissionSettings ds, uint64_t seed, int threads = 2) {
  PerspectiveCamera camera(ts.desc.camera, kSize, kSize);
  auto r = render_direct_emission(*ts.scene, camera, kSize, kSize, ds, seed, kDirectEmissionStream, ts.render.path,
                                  threads, nullptr);
  EXPECT_TRUE(r.ok()) << r.status().to_string();
  return r.ok() ? r->direct : Image(kSize, kSize, 3);
}

// Mean and standard error per pixel value of the PT `direct` layer over
// independent seeds: an estimate by different code (trace_path's depth 0).
constexpr int kReferenceSeeds = 8, kReferenceSpp = 1024;
constexpr double kReferenceSamples = double(kReferenceSeeds) * kReferenceSpp;
struct Reference {
  std::vector<double> mean, se;
};
const Reference& pt_direct_reference() {
  static Reference ref = [] {
    auto ts = load_test_scene("cbox", kSize, kSize);
    constexpr int kSeeds = kReferenceSeeds;
    std::vector<std::vector<double>> runs;
    for (int s = 0; s < kSeeds; ++s) {
      FrameRenderSettings rs = ts->render;
      rs.spp = kReferenceSpp;
      rs.seed = 5000 + uint64_t(s);
      auto r = render_frame_pt(*ts->scene, rs, 0, {});
      EXPECT_TRUE(r.ok());
      runs.emplace_back(r->direct.data().begin(), r->direct.data().end());
    }
    Reference out;
    const size_t n = runs[0].size();
    out.mean.assign(n, 0);
    out.se.assign(n, 0);
    for (size_t k = 0; k < n; ++k) {
      for (const auto& r : runs) out.mean[k] += r[k] / kSeeds;
      double ss = 0;
      for (const auto& r : runs) ss += (r[k] - out.mean[k]) * (r[k] - out.mean[k]);
      out.se[k] = std::sqrt(ss / (kSeeds - 1) / kSeeds);
    }
    return out;
  }();
  return ref;
}

// Sum over pixels of (estimate − reference)², the pass's squared error.
double squared_error(const Image& img) {
  const Reference& ref = pt_direct_reference();
  double e = 0;
  for (size_t k = 0; k < ref.mean.size(); ++k) e += (img.data()[k] - ref.mean[k]) * (img.data()[k] - ref.mean[k]);
  return e;
}

// Checks that the mean of `runs` (one image per seed) equals the PT reference
// within its noise. `samples` bounds the variance of one run's pixel: no
// worse than as many independent uniform camera samples (stratification only
// lowers it), taken from the reference's per-sample variance: a sample
// variance over the seeds would be 0 where the light covers a sliver hit by
// no stratum.
void expect_unbiased(const std::vector<std::vector<double>>& runs, int samples, const std::string& what) {
  const Reference& ref = pt_direct_reference();
  const double seeds = double(runs.size());
  double z2 = 0, z = 0;
  int tested = 0;
  for (size_t k = 0; k < ref.mean.size(); ++k) {
    double m = 0;
    for (const auto& r : runs) m += r[k] / seeds;
    const double per_sample = ref.se[k] * ref.se[k] * kReferenceSamples;
    const double var = per_sample / (double(samples) * seeds) + ref.se[k] * ref.se[k];
    if (var <= 1e-12) {
      // Both exact (fully inside or outside the light): they must agree.
      EXPECT_NEAR(m, ref.mean[k], 1e-4 * (1 + ref.mean[k])) << what << ": value " << k;
      continue;
    }
    const double zk = (m - ref.mean[k]) / std::sqrt(var);
    z2 += zk * zk;
    z += zk;
    ++tested;
  }
  ASSERT_GT(tested, 10) << what << ": the light's edge must cross some pixels";
  // E[z²] ≤ ~1.3 (the bound above, Student t of the reference's 7 dof); a
  // biased estimate gives far more.
  EXPECT_LT(z2 / tested, 2.0) << what;
  EXPECT_LT(std::abs(z) / std::sqrt(double(tested)), 4.0) << what;
}

TEST(DirectEmissionTest, MeanOverSeedsEqualsThePathTracersFirstHitEmission) {
  auto ts = load_test_scene("cbox", kSize, kSize);
  ASSERT_TRUE(ts);
  // Plain stratified (no edge refinement) and edge-adaptive: both unbiased.
  for (DirectEmissionSettings ds : {DirectEmissionSettings{2, 2}, DirectEmissionSettings{2, 8}}) {
    constexpr int kSeeds = 16;
    std::vector<std::vector<double>> runs;
    for (int s = 0; s < kSeeds; ++s) {
      Image img = direct_pass(*ts, ds, 100 + uint64_t(s));
      runs.emplace_back(img.data().begin(), img.data().end());
    }
    expect_unbiased(runs, ds.strata * ds.strata,
                    "strata " + std::to_string(ds.strata) + "/" + std::to_string(ds.edge_strata));
  }
}

// Pixels whose probes agree are left to the caller's paths (what G-PT and
// T-GPT do): they take no ray, and the merged estimate stays unbiased.
TEST(DirectEmissionTest, PixelsLeftToThePathsTakeNoRayAndTheMergedEstimateStaysUnbiased) {
  auto ts = load_test_scene("cbox", kSize, kSize);
  ASSERT_TRUE(ts);
  PerspectiveCamera camera(ts->desc.camera, kSize, kSize);
  // Probed everywhere, not by emitter bounds (tested below), so that the pixels that
  // see no emitter are left to the paths too.
  const DirectEmissionSettings own{2, 8, false, false}, left{2, 8, true, false};
  auto all = render_direct_emission(*ts->scene, camera, kSize, kSize, own, 7, 0, ts->render.path, 2, nullptr);
  auto some = render_direct_emission(*ts->scene, camera, kSize, kSize, left, 7, 0, ts->render.path, 2, nullptr);
  ASSERT_TRUE(all.ok() && some.ok());
  EXPECT_TRUE(all->from_paths.empty());
  ASSERT_EQ(some->from_paths.size(), size_t(kSize) * kSize);
  uint64_t left_count = 0;
  for (uint8_t f : some->from_paths) left_count += f;
  // cbox: most pixels see no emitter at all; the light's pixels are not uniform.
  EXPECT_GT(left_count, uint64_t(kSize * kSize / 2));
  EXPECT_LT(left_count, uint64_t(kSize * kSize));
  EXPECT_EQ(all->rays - some->rays, left_count) << "one ray fewer per pixel left to the paths";

  // The paths' estimate: PT's own first-hit emission at 4 spp (as many
  // samples as the pass's 2x2 strata, so the variance bound covers both).
  constexpr int kSeeds = 16;
  std::vector<std::vector<double>> runs;
  for (int s = 0; s < kSeeds; ++s) {
    auto pass = render_direct_emission(*ts->scene, camera, kSize, kSize, left, 100 + uint64_t(s), 0,
                                       ts->render.path, 2, nullptr);
    ASSERT_TRUE(pass.ok());
    FrameRenderSettings rs = ts->render;
    rs.spp = 4;
    rs.seed = 700 + uint64_t(s);
    auto pt = render_frame_pt(*ts->scene, rs, 0, {});
    ASSERT_TRUE(pt.ok());
    Image merged = merge_direct_estimates(std::move(*pass), pt->direct);
    runs.emplace_back(merged.data().begin(), merged.data().end());
  }
  expect_unbiased(runs, 4, "pass merged with the paths");
}

// Pixels outside every area emitter's projected bounds see no emission but
// the environment's. Without an environment (cbox, veach-mis) they take no
// probe and no sample and are 0; with one (matpreview, whose camera sees none
// of it) they take only their corner probes, which agree. Either way the
// result (merged with the paths' estimate as G-PT does, or the pass's own) is
// bit for bit the one probed everywhere, with fewer rays.
TEST(DirectEmissionTest, PixelsNoEmitterProjectsIntoAreZeroWithoutRays) {
  for (const char* name : {"cbox", "veach-mis", "matpreview"}) {
    auto ts = load_test_scene(name, kSize, kSize);
    ASSERT_TRUE(ts);
    PerspectiveCamera camera(ts->desc.camera, kSize, kSize);
    FrameRenderSettings rs = ts->render;
    rs.spp = 4;
    rs.seed = 21;
    auto pt = render_frame_pt(*ts->scene, rs, 0, {});
    ASSERT_TRUE(pt.ok());
    for (bool from_paths : {false, true}) {
      DirectEmissionResult r[2];
      for (int cull = 0; cull < 2; ++cull) {
        auto pass = render_direct_emission(*ts->scene, camera, kSize, kSize, {4, 16, from_paths, cull == 1}, 5, 0,
                                           ts->render.path, 2, nullptr);
        ASSERT_TRUE(pass.ok()) << pass.status().to_string();
        r[cull] = std::move(*pass);
      }
      const bool environment = std::string(name) == "matpreview";
      EXPECT_EQ(r[0].culled_pixels, 0u);
      if (environment) {
        EXPECT_EQ(r[1].culled_pixels, 0u) << name;
      } else {
        EXPECT_GT(r[1].culled_pixels, uint64_t(kSize * kSize / 4)) << name;
      }
      EXPECT_LT(r[1].rays, r[0].rays) << name;
      EXPECT_EQ(r[1].edge_pixels, r[0].edge_pixels) << name;
      const uint64_t rays_culled = r[1].rays, rays_all = r[0].rays;
      Image a = merge_direct_estimates(std::move(r[0]), pt->direct);
      Image b = merge_direct_estimates(std::move(r[1]), pt->direct);
      EXPECT_EQ(a.data(), b.data()) << name << (from_paths ? " merged with the paths" : " the pass alone");
      std::printf("[ direct ] %s from_paths=%d: %llu rays, %llu with culling\n", name, int(from_paths),
                  (unsigned long long)rays_all, (unsigned long long)rays_culled);
    }
  }
}

// A visible environment (the stiff suite's sky with a sun): pixels outside
// the area emitters' bounds start from their corner probes; the sky's own
// pixels agree there and are left to the paths, and the silhouettes of the
// floor and the ball against the sky still get edge strata, as when every
// pixel takes all nine probes.
TEST(DirectEmissionTest, VisibleEnvironmentIsRefinedWhereCornerProbesDiffer) {
  constexpr int kRes = 32;
  LoadOptions load;
  load.params = {{"res", std::to_string(kRes)}, {"envmap", stiff::sun_envmap_path()}};
  auto desc = load_mitsuba_scene(stiff::stiff_dir() + "/envmap_sun.xml", load);
  ASSERT_TRUE(desc.ok()) << desc.status().to_string();
  auto fs = FrameScene::create(desc.value(), {});
  ASSERT_TRUE(fs.ok());
  PerspectiveCamera camera(desc->camera, kRes, kRes);
  PathTracerSettings path;
  DirectEmissionResult r[2];
  for (int bounds = 0; bounds < 2; ++bounds) {
    auto pass = render_direct_emission(*fs.value(), camera, kRes, kRes, {4, 16, true, bounds == 1}, 3, 0, path, 2,
                                       nullptr);
    ASSERT_TRUE(pass.ok()) << pass.status().to_string();
    r[bounds] = std::move(*pass);
  }
  ASSERT_GT(r[0].edge_pixels, uint64_t(kRes)) << "the silhouettes against the sky";
  EXPECT_GE(double(r[1].edge_pixels), 0.9 * double(r[0].edge_pixels));
  EXPECT_LE(r[1].edge_pixels, r[0].edge_pixels);
  EXPECT_EQ(r[1].culled_pixels, 0u) << "the environment can be seen anywhere";
  EXPECT_LT(double(r[1].rays), 0.9 * double(r[0].rays));
  uint64_t sky_left = 0;
  for (uint8_t f : r[1].from_paths) sky_left += f;
  EXPECT_GT(sky_left, uint64_t(kRes * kRes / 4)) << "uniform sky and floor pixels";
  std::printf("[ direct ] envmap_sun: %llu rays, %llu edge pixels; by bounds %llu rays, %llu edge pixels\n",
              (unsigned long long)r[0].rays, (unsigned long long)r[0].edge_pixels, (unsigned long long)r[1].rays,
              (unsigned long long)r[1].edge_pixels);
}

// Inside the closed furnace every wall emits Le = 1: every pixel's probes
// agree, so the pass traces only its probes and the paths fill in every pixel
// (the mean of two sets of paths when both passes of T-GPT give one).
TEST(DirectEmissionTest, UniformEmissionIsTakenFromThePaths) {
  LoadOptions load;
  load.params = {{"res", "16"}, {"max_depth", "2"}};
  auto desc = load_mitsuba_scene(std::string(GDVR_SOURCE_DIR) + "/scenes/stiff/furnace.xml", load);
  ASSERT_TRUE(desc.ok()) << desc.status().to_string();
  auto fs = FrameScene::create(desc.value(), {});
  ASSERT_TRUE(fs.ok());
  constexpr int kRes = 16;
  PerspectiveCamera camera(desc->camera, kRes, kRes);
  PathTracerSettings path;
  path.max_depth = 2;
  auto pass = render_direct_emission(*fs.value(), camera, kRes, kRes, {4, 16, true}, 1, 0, path, 2, nullptr);
  ASSERT_TRUE(pass.ok());
  EXPECT_EQ(pass->rays, uint64_t(2 * kRes + 1) * uint64_t(2 * kRes + 1)) << "probes only";
  ASSERT_EQ(pass->from_paths.size(), size_t(kRes) * kRes);
  for (uint8_t f : pass->from_paths) EXPECT_EQ(f, 1);
  for (float v : pass->direct.data()) EXPECT_EQ(v, 0.0f) << "no estimate of its own";

  FrameRenderSettings rs;
  rs.width = rs.height = kRes;
  rs.spp = 2;
  rs.path = path;
  auto pt = render_frame_pt(*fs.value(), rs, 0, {});
  ASSERT_TRUE(pt.ok());
  Image half(kRes, kRes, 3);  // a second set of paths that saw half the radiance
  for (float& v : half.data()) v = 0.5f;
  Image merged = merge_direct_estimates(std::move(*pass), pt->direct, &half);
  for (float v : merged.data()) EXPECT_FLOAT_EQ(v, 0.75f);
}

TEST(DirectEmissionTest, StrataAndEdgeRefinementLowerTheErrorOfTheLightsEdges) {
  auto ts = load_test_scene("cbox", kSize, kSize);
  ASSERT_TRUE(ts);
  // 16 random camera samples (what the paths' own direct estimate gets at
  // 16 spp) against 16 stratified rays, and against 16 + edge refinement.
  double random16 = 0, stratified16 = 0, adaptive = 0;
  constexpr int kSeeds = 8;
  for (int s = 0; s < kSeeds; ++s) {
    FrameRenderSettings rs = ts->render;
    rs.spp = 16;
    rs.seed = 300 + uint64_t(s);
    auto pt = render_frame_pt(*ts->scene, rs, 0, {});
    ASSERT_TRUE(pt.ok());
    random16 += squared_error(pt->direct);
    stratified16 += squared_error(direct_pass(*ts, {4, 4}, 300 + uint64_t(s)));
    adaptive += squared_error(direct_pass(*ts, {4, 16}, 300 + uint64_t(s)));
  }
  EXPECT_LT(stratified16, 0.5 * random16);
  EXPECT_LT(adaptive, 0.25 * stratified16);
}

TEST(DirectEmissionTest, DeterministicAcrossThreadCountsAndBlackWithHiddenEmitters) {
  auto ts = load_test_scene("cbox", kSize, kSize);
  ASSERT_TRUE(ts);
  const Image one = direct_pass(*ts, {4, 16}, 9, /*threads=*/1);
  const Image two = direct_pass(*ts, {4, 16}, 9, /*threads=*/2);
  EXPECT_EQ(one.data(), two.data());

  PathTracerSettings hidden = ts->render.path;
  hidden.hide_emitters = true;
  PerspectiveCamera camera(ts->desc.camera, kSize, kSize);
  auto r = render_direct_emission(*ts->scene, camera, kSize, kSize, {4, 16}, 9, 0, hidden, 2, nullptr);
  ASSERT_TRUE(r.ok());
  for (float v : r->direct.data()) EXPECT_EQ(v, 0.0f);
  EXPECT_EQ(r->rays, 0u);
}

TEST(DirectEmissionTest, RejectsBadStrata) {
  auto ts = load_test_scene("cbox", kSize, kSize);
  ASSERT_TRUE(ts);
  PerspectiveCamera camera(ts->desc.camera, kSize, kSize);
  EXPECT_FALSE(
      render_direct_emission(*ts->scene, camera, kSize, kSize, {0, 4}, 1, 0, ts->render.path, 1, nullptr).ok());
  EXPECT_FALSE(
      render_direct_emission(*ts->scene, camera, kSize, kSize, {8, 4}, 1, 0, ts->render.path, 1, nullptr).ok());
}

}  // namespace
}  // namespace gdvr
