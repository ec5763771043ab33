// The stratified, edge-adaptive pass for emitters seen directly from the
// camera (core/render/direct_emission.h): unbiased against the path tracer's
// own first-hit emission, less noisy than the path samples it replaces,
// deterministic, and black with hide_emitters.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/render/direct_emission.h"
#include "tests/core/gradient/gpt_test_util.h"

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

TEST(DirectEmissionTest, MeanOverSeedsEqualsThePathTracersFirstHitEmission) {
  auto ts = load_test_scene("cbox", kSize, kSize);
  ASSERT_TRUE(ts);
  const Reference& ref = pt_direct_reference();
  // Plain stratified (no edge refinement) and edge-adaptive: both unbiased.
  for (DirectEmissionSettings ds : {DirectEmissionSettings{2, 2}, DirectEmissionSettings{2, 8}}) {
    constexpr int kSeeds = 16;
    std::vector<std::vector<double>> runs;
    for (int s = 0; s < kSeeds; ++s) {
      Image img = direct_pass(*ts, ds, 100 + uint64_t(s));
      runs.emplace_back(img.data().begin(), img.data().end());
    }
    double z2 = 0, z = 0;
    int tested = 0;
    for (size_t k = 0; k < ref.mean.size(); ++k) {
      double m = 0;
      for (const auto& r : runs) m += r[k] / kSeeds;
      // The variance of the pass's mean is bounded by that of as many
      // independent uniform samples (stratification only lowers it), taken
      // from the reference's per-sample variance: a sample variance over the
      // seeds would be 0 where the light covers a sliver hit by no stratum.
      const double per_sample = ref.se[k] * ref.se[k] * kReferenceSamples;
      const double var = per_sample / double(ds.strata * ds.strata * kSeeds) + ref.se[k] * ref.se[k];
      if (var <= 1e-12) {
        // Both exact (fully inside or outside the light): they must agree.
        EXPECT_NEAR(m, ref.mean[k], 1e-4 * (1 + ref.mean[k])) << "value " << k;
        continue;
      }
      const double zk = (m - ref.mean[k]) / std::sqrt(var);
      z2 += zk * zk;
      z += zk;
      ++tested;
    }
    ASSERT_GT(tested, 10) << "the light's edge must cross some pixels";
    // E[z²] ≤ ~1.3 (the bound above, Student t of the reference's 7 dof); a
    // biased pass gives far more.
    EXPECT_LT(z2 / tested, 2.0) << "strata " << ds.strata << "/" << ds.edge_strata;
    EXPECT_LT(std::abs(z) / std::sqrt(double(tested)), 4.0) << "strata " << ds.strata << "/" << ds.edge_strata;
  }
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
