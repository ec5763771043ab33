#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>

#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

// A few grossly wrong gradients (a "firefly" in the gradient buffers) in frame 0.
void plant_outlier_gradients(GradientWindow& w) {
  const int spots[][2] = {{5, 5}, {30, 8}, {12, 25}, {25, 20}};
  for (auto& s : spots)
    for (int c = 0; c < 3; ++c) {
      test::mutable_frame(w, 0).buffer(Term::kDx).at(s[0], s[1], c) += 4.0f;
      test::mutable_frame(w, 0).buffer(Term::kDy).at(s[0] + 1, s[1] + 2, c) -= 3.0f;
    }
}

// They smear into a halo under L2 but are voted down under L1 (docs/reconstruction.md).
TEST(IrlsL1Test, RobustToPlantedOutlierGradientsWhereL2IsNot) {
  for (int frames : {1, 3}) {
    test::SceneOptions o;
    o.frames = frames;
    o.temporal = frames > 1;
    o.primal_sigma = 0.01f;
    GradientWindow w = test::make_window(o);
    plant_outlier_gradients(w);
    ReconSettings l2, l1;
    l1.method = ReconMethod::kL1;
    auto r2 = reconstruct(w, l2);
    auto r1 = reconstruct(w, l1);
    ASSERT_TRUE(r1.ok() && r2.ok());
    const auto e2 = test::frame_error(r2->frames[0], 0);
    const auto e1 = test::frame_error(r1->frames[0], 0);
    EXPECT_GT(e2.max, 0.5) << "L2 should visibly suffer";
    EXPECT_LT(e1.max, 0.2 * e2.max);
    EXPECT_LT(e1.rms, 0.25 * e2.rms);
  }
}

// With a denoised data term (a trust map in the window) the rounds start from
// the denoiser's image and stop after l1_denoised_outer_iterations: two
// reweightings still vote the planted outliers down, for fewer CG iterations
// than the full schedule from the same start.
TEST(IrlsL1Test, FromADenoisedDataTermFewRoundsKeepTheOutliersOut) {
  for (int frames : {1, 3}) {
    SCOPED_TRACE(frames);
    test::SceneOptions o;
    o.frames = frames;
    o.temporal = frames > 1;
    o.primal_sigma = 0.01f;  // the denoiser's image: close to the truth
    GradientWindow w = test::make_window(o);
    plant_outlier_gradients(w);
    GradientWindow plain;  // the same buffers without the map (the frames are shared: copy them)
    for (const auto& f : w.frames) plain.frames.push_back(std::make_shared<GradientFrame>(*f));
    for (int t = 0; t < frames; ++t) {
      Image map(o.width, o.height, 1);
      for (float& v : map.data()) v = 1.0f;  // α unchanged: only the schedule differs
      test::mutable_frame(w, t).data_weight = map;
    }
    ReconSettings l2, l1;
    l1.method = ReconMethod::kL1;
    auto r2 = reconstruct(w, l2);
    auto r1 = reconstruct(w, l1);
    auto full = reconstruct(plain, l1);
    ASSERT_TRUE(r1.ok() && r2.ok() && full.ok());
    EXPECT_EQ(r1->stats.outer_iterations, l1.l1_denoised_outer_iterations);
    EXPECT_EQ(full->stats.outer_iterations, l1.l1_outer_iterations);
    EXPECT_LT(r1->stats.cg_iterations, full->stats.cg_iterations);
    const auto e2 = test::frame_error(r2->frames[0], 0);
    const auto e1 = test::frame_error(r1->frames[0], 0);
    EXPECT_GT(e2.max, 0.5) << "L2 should visibly suffer";
    EXPECT_LT(e1.max, 0.2 * e2.max);
    EXPECT_LT(e1.rms, 0.25 * e2.rms);
  }
}

TEST(IrlsL1Test, ConvergesTowardsL2OnCleanData) {
  test::SceneOptions o;
  o.primal_sigma = 0.05f;
  o.gradient_sigma = 0.005f;
  GradientWindow w = test::make_window(o);
  ReconSettings l1;
  l1.method = ReconMethod::kL1;
  auto r1 = reconstruct(w, l1);
  ASSERT_TRUE(r1.ok());
  EXPECT_LT(test::frame_error(r1->frames[0], 0).rms, 0.02);
  EXPECT_GT(r1->stats.cg_iterations, 0);
  EXPECT_EQ(r1->stats.outer_iterations, l1.l1_outer_iterations);
}

// Light carried by rare paths: the primal of a flat image of value v is v/p
// at a fraction p of the pixels and 0 elsewhere (unbiased, mean v), the
// gradients exact (0). L1 alone tends to the median, 0; with the primal's low
// frequencies given back it keeps the primal's energy, as L2 does.
TEST(IrlsL1Test, KeepsTheEnergyOfRareBrightSamples) {
  const int w = 48, h = 40;
  const float v = 0.3f, p = 0.05f;
  std::mt19937 rng(3);
  std::bernoulli_distribution lit(p);
  for (int frames : {1, 4}) {
    GradientWindow win;
    double primal_sum = 0;
    for (int t = 0; t < frames; ++t) {
      auto f = std::make_shared<GradientFrame>();
      for (Term term : kAllTerms) {
        if (is_temporal(term) && frames == 1) continue;
        f->buffer(term) = Image(w, h, 3);
      }
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const float value = lit(rng) ? v / p : 0.0f;
          for (int c = 0; c < 3; ++c) f->buffer(Term::kPrimal).at(x, y, c) = value;
          primal_sum += 3.0 * value;
        }
      win.frames.push_back(f);
    }
    const double primal_mean = primal_sum / (3.0 * w * h * frames);
    auto mean_of = [&](const ReconResult& r) {
      double s = 0;
      for (const Image& im : r.frames)
        for (float x : im.data()) s += x;
      return s / (3.0 * w * h * frames);
    };
    ReconSettings l1;
    l1.method = ReconMethod::kL1;
    ReconSettings median_only = l1;
    median_only.l1_low_frequencies_from_primal = false;
    auto kept = reconstruct(win, l1);
    auto lost = reconstruct(win, median_only);
    ASSERT_TRUE(kept.ok() && lost.ok());
    EXPECT_LT(mean_of(*lost), 0.5 * primal_mean) << frames << " frame(s): L1 alone should lose the rare samples";
    EXPECT_NEAR(mean_of(*kept), primal_mean, 0.03 * primal_mean) << frames << " frame(s)";
    // And no pixel is left near the fireflies' value: the energy is spread
    // smoothly, not kept as spikes.
    float peak = 0;
    for (const Image& im : kept->frames)
      for (float x : im.data()) peak = std::max(peak, x);
    EXPECT_LT(peak, 0.5f * v / p);
  }
}

}  // namespace
}  // namespace gdvr
