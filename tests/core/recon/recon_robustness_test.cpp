// Numerics that must hold whatever the renderer feeds in: NaN/Inf samples,
// absurd α, degenerate windows, and the equivalences between window shapes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/recon/reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

using test::SceneOptions;

ReconSettings with_method(ReconMethod m) {
  ReconSettings s;
  s.method = m;
  return s;
}

class ReconRobustnessTest : public ::testing::TestWithParam<ReconMethod> {};

TEST_P(ReconRobustnessTest, NonFiniteSamplesAreDroppedAndCounted) {
  SceneOptions o;
  o.frames = 3;
  o.temporal = true;
  o.primal_sigma = 0.02f;
  o.variances = true;
  GradientWindow w = test::make_window(o);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  GradientFrame& f0 = test::mutable_frame(w, 0);
  f0.buffer(Term::kDx).at(3, 4, 0) = nan;
  f0.buffer(Term::kDy).at(10, 5, 2) = inf;
  f0.buffer(Term::kDt).at(7, 7, 1) = -inf;
  f0.buffer(Term::kDxdt).at(8, 8, 0) = nan;
  f0.buffer(Term::kPrimal).at(20, 20, 1) = nan;
  test::mutable_frame(w, 1).variance(Term::kDx).at(5, 5, 0) = nan;
  auto r = reconstruct(w, with_method(GetParam()));
  ASSERT_TRUE(r.ok()) << r.status().to_string();
  for (const Image& img : r->frames) EXPECT_TRUE(test::all_finite(img));
  EXPECT_EQ(r->stats.non_finite_outputs, 0);
  EXPECT_EQ(r->stats.non_finite_constraints[term_index(Term::kDx)], 2);
  EXPECT_EQ(r->stats.non_finite_constraints[term_index(Term::kDy)], 1);
  EXPECT_EQ(r->stats.non_finite_constraints[term_index(Term::kDt)], 1);
  EXPECT_EQ(r->stats.non_finite_constraints[term_index(Term::kPrimal)], 1);
  EXPECT_EQ(r->stats.total_non_finite(), 6);
  if (GetParam() != ReconMethod::kNone) {
    // The dropped primal pixel is filled in from its neighbours' gradients.
    EXPECT_LT(std::fabs(r->frames[0].at(20, 20, 1) - test::scene_value(20, 20, 0, 1)), 0.1);
  }
}

TEST_P(ReconRobustnessTest, AllInfGradientsGiveFinitePrimal) {
  SceneOptions o;
  o.variances = true;
  GradientWindow w = test::make_window(o);
  for (float& v : test::mutable_frame(w, 0).buffer(Term::kDx).data()) v = std::numeric_limits<float>::infinity();
  for (float& v : test::mutable_frame(w, 0).buffer(Term::kDy).data()) v = std::numeric_limits<float>::quiet_NaN();
  auto r = reconstruct(w, with_method(GetParam()));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(test::all_finite(r->frames[0]));
  EXPECT_LT(test::frame_error(r->frames[0], 0).max, 1e-4);  // nothing but the primal is left
}

INSTANTIATE_TEST_SUITE_P(Recon, ReconRobustnessTest,
                         ::testing::Values(ReconMethod::kNone, ReconMethod::kL2, ReconMethod::kL1,
                                           ReconMethod::kUniform, ReconMethod::kWeighted),
                         [](const auto& info) { return std::string(recon_method_name(info.param)); });

TEST(ReconAlphaTest, AbsurdAlphaIsRejected) {
  GradientWindow w = test::make_window(SceneOptions());
  for (double a : {0.0, -0.2, std::nan(""), HUGE_VAL}) {
    ReconSettings s;
    s.alpha = a;
    auto r = reconstruct(w, s);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find("alpha"), std::string::npos);
  }
}

TEST(ReconAlphaTest, TinyAndHugeAlphaStayFinite) {
  SceneOptions o;
  o.primal_sigma = 0.05f;
  o.gradient_sigma = 0.02f;
  GradientWindow w = test::make_window(o);
  for (ReconMethod m : {ReconMethod::kL2, ReconMethod::kL1}) {
    for (double a : {1e-12, 1e-6, 1e6, 1e30, 1e200}) {
      ReconSettings s = with_method(m);
      s.alpha = a;
      auto r = reconstruct(w, s);
      ASSERT_TRUE(r.ok()) << a;
      EXPECT_TRUE(test::all_finite(r->frames[0])) << recon_method_name(m) << " alpha=" << a;
      EXPECT_EQ(r->stats.non_finite_outputs, 0);
      if (a >= 1e6) {
        // The primal dominates: the result is the primal.
        const Image& p = w.frames[0]->buffer(Term::kPrimal);
        for (size_t i = 0; i < p.data().size(); ++i) ASSERT_NEAR(r->frames[0].data()[i], p.data()[i], 1e-3);
      }
    }
  }
}

TEST(ReconWindowTest, SingleFrameWindowEqualsSpatialSolver) {
  SceneOptions o;
  o.temporal = true;  // dt buffers present, but W = 1 has no frame t+1
  o.primal_sigma = 0.05f;
  o.gradient_sigma = 0.01f;
  GradientWindow w = test::make_window(o);
  GradientFrame spatial = *w.frames[0];
  for (Term t : {Term::kDt, Term::kDxdt, Term::kDydt}) spatial.buffer(t) = Image(), spatial.variance(t) = Image();
  for (ReconMethod m : {ReconMethod::kL2, ReconMethod::kL1}) {
    auto a = reconstruct(w, with_method(m));
    auto b = reconstruct_frame(spatial, with_method(m));
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->frames[0].data(), b->frames[0].data()) << recon_method_name(m);
  }
}

TEST(ReconWindowTest, WindowWithoutTemporalTermsSolvesFramesIndependently) {
  SceneOptions o;
  o.frames = 3;
  o.primal_sigma = 0.05f;
  o.gradient_sigma = 0.01f;
  GradientWindow w = test::make_window(o);
  ReconSettings s;
  s.l2_tolerance = 1e-6;
  auto joint = reconstruct(w, s);
  ASSERT_TRUE(joint.ok());
  for (int t = 0; t < 3; ++t) {
    auto single = reconstruct_frame(*w.frames[t], s);
    ASSERT_TRUE(single.ok());
    for (size_t i = 0; i < single->frames[0].data().size(); ++i)
      ASSERT_NEAR(joint->frames[t].data()[i], single->frames[0].data()[i], 1e-4);
  }
}

TEST(ReconWindowTest, TwoFrameWindowIsExactAndUsesTemporalTerms) {
  SceneOptions o;
  o.frames = 2;
  o.temporal = true;
  o.primal_sigma = 0.1f;
  GradientWindow w = test::make_window(o);
  ReconSettings s;
  s.l2_tolerance = 1e-6;
  auto r = reconstruct(w, s);
  ASSERT_TRUE(r.ok());
  // Temporal terms tie the frames: noise is averaged over twice the pixels.
  GradientWindow spatial = test::make_window([&] { SceneOptions q = o; q.temporal = false; return q; }());
  auto r_sp = reconstruct(spatial, s);
  ASSERT_TRUE(r_sp.ok());
  const double e_t = test::frame_error(r->frames[0], 0).rms + test::frame_error(r->frames[1], 1).rms;
  const double e_s = test::frame_error(r_sp->frames[0], 0).rms + test::frame_error(r_sp->frames[1], 1).rms;
  EXPECT_LT(e_t, 0.85 * e_s);
  EXPECT_LT(e_t, 0.05);
}

TEST(ReconWindowTest, MaskedTemporalConstraintsAreDroppedAndCounted) {
  SceneOptions o;
  o.frames = 3;
  o.temporal = true;
  GradientWindow w = test::make_window(o);
  // Corrupt dt where the mask drops it: the result must not see the garbage.
  GradientFrame& f = test::mutable_frame(w, 0);
  f.mask(Term::kDt).assign(size_t(o.width) * o.height, 1);
  for (int x = 0; x < o.width; ++x) {
    f.mask(Term::kDt)[size_t(10) * o.width + x] = 0;
    for (int c = 0; c < 3; ++c) f.buffer(Term::kDt).at(x, 10, c) = 5.0f;
  }
  ReconSettings s;
  s.l2_tolerance = 1e-6;
  auto r = reconstruct(w, s);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->stats.masked_constraints[term_index(Term::kDt)], o.width);
  for (int t = 0; t < 3; ++t) EXPECT_LT(test::frame_error(r->frames[t], t).max, 2e-3);
}

TEST(ReconWindowTest, RejectsMismatchedFrames) {
  GradientWindow w = test::make_window(SceneOptions());
  SceneOptions other;
  other.width = 10;
  w.frames.push_back(test::make_window(other).frames[0]);
  auto r = reconstruct(w, ReconSettings());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("frame 1"), std::string::npos) << r.status().message();
  EXPECT_FALSE(reconstruct(GradientWindow(), ReconSettings()).ok());
}

}  // namespace
}  // namespace gdvr
