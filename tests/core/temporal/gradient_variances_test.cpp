// tgpt_gradient_frame's two modes (core/temporal/temporal_buffers.h): folding
// the gradients' variances into their values (NaN where a variance is not
// finite or negative) gives every solver that weighs nothing by variance the
// result and the counts of keeping them, bit for bit, with 7 RGB images per
// frame instead of 12.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "core/job/job_runner.h"
#include "core/recon/reconstruct.h"
#include "core/temporal/temporal_buffers.h"
#include "tests/core/temporal/render_buffers.h"

namespace gdvr {
namespace {

// Two frames of the demo with the small box moving, T-GPT's stage-1 buffers.
std::map<int, FrameBuffers> moving_pair() {
  JobSpec job;
  job.scene = "cbox_demo.xml";
  job.frames = "0,6";
  job.fps = 24;
  job.width = job.height = 16;
  job.spp = 4;
  job.seed = 11;
  job.integrator = Integrator::kTgpt;
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  job.animation.tracks.push_back(box);
  return test::render_buffers(job, std::string(GDVR_SOURCE_DIR) + "/scenes/demo", {0, 6});
}

void set(LayeredImage& L, const std::string& layer, int pixel, int channel, float v) {
  for (ImageLayer& l : L.layers)
    if (l.name == layer) {
      l.image.data()[size_t(pixel) * 3 + channel] = v;
      return;
    }
  ADD_FAILURE() << "no layer " << layer;
}

GradientWindow window_of(const std::map<int, FrameBuffers>& b, GradientVariances variances) {
  GradientWindow w;
  auto tg = temporal_gradients(b.at(0).layers, b.at(6).layers, TgptSettings{});
  EXPECT_TRUE(tg.ok()) << tg.status().to_string();
  // A temporal variance that overflowed, and one a NaN sample poisoned.
  tg->dt_var.data()[7 * 3 + 0] = std::numeric_limits<float>::infinity();
  tg->dydt_var.data()[40 * 3 + 2] = std::numeric_limits<float>::quiet_NaN();
  auto f0 = tgpt_gradient_frame(b.at(0).layers, &tg.value(), variances);
  auto f1 = tgpt_gradient_frame(b.at(6).layers, nullptr, variances);
  EXPECT_TRUE(f0.ok() && f1.ok());
  w.frames.push_back(std::make_shared<const GradientFrame>(std::move(f0.value())));
  w.frames.push_back(std::make_shared<const GradientFrame>(std::move(f1.value())));
  return w;
}

TEST(GradientVariancesTest, FoldingGivesTheKeptResultBitForBit) {
  std::map<int, FrameBuffers> b = moving_pair();
  ASSERT_EQ(b.size(), 2u);
  // Spatial variances a solver must drop: infinite, negative, NaN, in one pass each.
  set(b[0].layers, "a_dx_var", 3, 1, std::numeric_limits<float>::infinity());
  set(b[0].layers, "b_dy_var", 20, 0, -1.0f);
  set(b[6].layers, "a_dx_var", 100, 2, std::numeric_limits<float>::quiet_NaN());

  const GradientWindow kept = window_of(b, GradientVariances::kKeep);
  const GradientWindow folded = window_of(b, GradientVariances::kFoldIntoValues);
  for (Term t : kAllTerms) {
    EXPECT_FALSE(kept.frames[0]->variance(t).empty()) << term_name(t);
    EXPECT_EQ(folded.frames[0]->variance(t).empty(), t != Term::kPrimal) << term_name(t);
  }

  for (ReconMethod m : {ReconMethod::kL2, ReconMethod::kL1, ReconMethod::kUniform}) {
    ASSERT_FALSE(uses_constraint_variances(m));
    ReconSettings s;
    s.method = m;
    auto a = reconstruct(kept, s);
    auto c = reconstruct(folded, s);
    ASSERT_TRUE(a.ok() && c.ok()) << recon_method_name(m);
    for (size_t f = 0; f < 2; ++f) EXPECT_EQ(a->frames[f].data(), c->frames[f].data()) << recon_method_name(m);
    // The poisoned constraints are dropped and counted as non-finite either way.
    EXPECT_EQ(a->stats.non_finite_constraints, c->stats.non_finite_constraints) << recon_method_name(m);
    EXPECT_EQ(a->stats.masked_constraints, c->stats.masked_constraints) << recon_method_name(m);
    EXPECT_GE(a->stats.non_finite_constraints[term_index(Term::kDx)], 2);
    EXPECT_GE(a->stats.non_finite_constraints[term_index(Term::kDy)], 1);
  }

  // The weighted solver needs what folding leaves out, and says so.
  ASSERT_TRUE(uses_constraint_variances(ReconMethod::kWeighted));
  ReconSettings w;
  w.method = ReconMethod::kWeighted;
  EXPECT_TRUE(reconstruct(kept, w).ok());
  auto refused = reconstruct(folded, w);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("no variance"), std::string::npos) << refused.status().to_string();
}

}  // namespace
}  // namespace gdvr
