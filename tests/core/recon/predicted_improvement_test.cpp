#include "core/recon/predicted_improvement.h"

#include <gtest/gtest.h>

#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

// White noise around a zero image: the prediction (docs/reconstruction.md,
// "Predicted improvement") must
// match the error the L2 solver actually achieves.
double monte_carlo_improvement(int frames, float sp, float sg, const ReconSettings& s) {
  double mse_primal = 0, mse_recon = 0;
  size_t n = 0;
  for (unsigned seed = 1; seed <= 2; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    GradientWindow w;
    for (int t = 0; t < frames; ++t) {
      auto f = std::make_shared<GradientFrame>();
      for (Term term : kAllTerms) {
        if (is_temporal(term) && frames == 1) continue;
        Image img(96, 96, 3);
        for (float& v : img.data()) v = (term == Term::kPrimal ? sp : sg) * gauss(rng);
        f->buffer(term) = std::move(img);
      }
      w.frames.push_back(std::move(f));
    }
    auto r = reconstruct(w, s);
    EXPECT_TRUE(r.ok());
    for (int t = 0; t < frames; ++t)
      for (size_t i = 0; i < r->frames[t].data().size(); ++i) {
        mse_primal += sqr(w.frames[t]->buffer(Term::kPrimal).data()[i]);
        mse_recon += sqr(r->frames[t].data()[i]);
        ++n;
      }
  }
  return mse_primal / mse_recon;
}

TEST(PredictedImprovementTest, MatchesMonteCarloForWhiteNoise) {
  for (auto [sp, sg, alpha] : {std::tuple{0.1f, 0.03f, 0.2}, std::tuple{0.1f, 0.1f, 0.2}, std::tuple{0.1f, 0.02f, 0.5}}) {
    ReconSettings s;
    s.alpha = alpha;
    NoiseLevels noise;
    noise[Term::kPrimal] = sp * sp;
    noise[Term::kDx] = noise[Term::kDy] = sg * sg;
    auto predicted = predicted_improvement(noise, s, /* temporal = */ false);
    ASSERT_TRUE(predicted.ok());
    const double measured = monte_carlo_improvement(1, sp, sg, s);
    RecordProperty("ratio_alpha" + std::to_string(alpha) + "_sg" + std::to_string(sg), std::to_string(measured / predicted.value()));
    EXPECT_NEAR(measured / predicted.value(), 1.0, 0.2) << "predicted " << predicted.value() << " measured " << measured;
  }
}

TEST(PredictedImprovementTest, TemporalPredictionIsBetterThanSpatialAndRoughlyRight) {
  ReconSettings s;
  NoiseLevels noise;
  noise[Term::kPrimal] = 0.01;
  for (Term t : {Term::kDx, Term::kDy, Term::kDt, Term::kDxdt, Term::kDydt}) noise[t] = 0.0009;
  const double spatial = predicted_improvement(noise, s, false).value();
  const double temporal = predicted_improvement(noise, s, true).value();
  EXPECT_GT(temporal, spatial);
  // A 6-frame window has borders in time the prediction ignores: loose bound.
  const double measured = monte_carlo_improvement(6, 0.1f, 0.03f, s);
  RecordProperty("ratio_temporal", std::to_string(measured / temporal));
  EXPECT_NEAR(measured / temporal, 1.0, 0.35) << "predicted " << temporal << " measured " << measured;
}

TEST(PredictedImprovementTest, MeasuresVarianceBuffersAndValidates) {
  test::SceneOptions o;
  o.primal_sigma = 0.1f;
  o.gradient_sigma = 0.05f;
  o.variances = true;
  auto levels = measure_noise_levels(test::make_window(o));
  ASSERT_TRUE(levels.ok());
  EXPECT_NEAR(levels.value()[Term::kPrimal], 0.01, 1e-6);
  EXPECT_NEAR(levels.value()[Term::kDx], 0.0025, 1e-6);
  EXPECT_FALSE(measure_noise_levels(test::make_window(test::SceneOptions())).ok());
  NoiseLevels zero;
  EXPECT_FALSE(predicted_improvement(zero, ReconSettings(), false).ok());
}

}  // namespace
}  // namespace gdvr
