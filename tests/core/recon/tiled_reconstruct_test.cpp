// The tiled window solve (core/recon/tiled_reconstruct.h) against the
// whole-frame solve, for every method, on synthetic windows of several tiles:
// the agreement bounds of docs/reconstruction.md ("Tiled solve"), no seams
// along tile borders, dropped constraints counted once, and the halo chosen
// from the operator's impulse response.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "core/image/error_metrics.h"
#include "core/recon/impulse_response.h"
#include "core/recon/reconstruct.h"
#include "core/recon/tile_grid.h"
#include "core/recon/tile_seams.h"
#include "core/recon/tiled_reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

// ---- TileGrid ----

TEST(TileGridTest, CoresCoverTheFrameOnceAndHalosStayInside) {
  auto g = TileGrid::create(1000, 530, 256, 40);
  ASSERT_TRUE(g.ok()) << g.status().to_string();
  EXPECT_EQ(g->columns(), 4);
  EXPECT_EQ(g->rows(), 3);
  std::vector<int> covered(size_t(1000) * 530, 0);
  for (const ReconTile& t : g->tiles()) {
    EXPECT_LE(t.core.width(), 256);
    EXPECT_LE(t.core.height(), 256);
    // Near-equal cores: no sliver at the right or bottom.
    EXPECT_GE(t.core.width(), 1000 / 4 - 1);
    EXPECT_GE(t.core.height(), 530 / 3 - 1);
    EXPECT_TRUE(t.padded.contains(t.core));
    EXPECT_TRUE(PixelRect::whole(1000, 530).contains(t.padded));
    EXPECT_EQ(t.padded.x0, std::max(0, t.core.x0 - 40));
    EXPECT_EQ(t.padded.y1, std::min(530, t.core.y1 + 40));
    for (int y = t.core.y0; y < t.core.y1; ++y)
      for (int x = t.core.x0; x < t.core.x1; ++x) ++covered[size_t(y) * 1000 + x];
  }
  for (int c : covered) ASSERT_EQ(c, 1);
}

TEST(TileGridTest, FrameNoLargerThanATileIsOneTile) {
  auto g = TileGrid::create(64, 48, 64, 10);
  ASSERT_TRUE(g.ok());
  ASSERT_EQ(g->count(), 1);
  EXPECT_EQ(g->tile(0).core, PixelRect::whole(64, 48));
  EXPECT_EQ(g->tile(0).padded, PixelRect::whole(64, 48));
}

TEST(TileGridTest, BadInputIsAnErrorNamingIt) {
  EXPECT_NE(TileGrid::create(0, 10, 16, 4).status().message().find("frame"), std::string::npos);
  EXPECT_NE(TileGrid::create(10, 10, 0, 4).status().message().find("tile_size"), std::string::npos);
  EXPECT_NE(TileGrid::create(10, 10, 16, -1).status().message().find("halo"), std::string::npos);
  ReconSettings s;
  s.tile_size = 3;
  EXPECT_NE(s.validate().message().find("tile_size"), std::string::npos);
  s.tile_size = 0;  // no tiling
  EXPECT_TRUE(s.validate().ok());
  s.tile_halo = -2;
  EXPECT_NE(s.validate().message().find("tile_halo"), std::string::npos);
}

// ---- Tiled against whole-frame solves ----

// 160×120, 4 frames with temporal terms, noisy primal and gradients: 3×3
// tiles of at most 56 pixels a side, so every tile has neighbours and the
// inner tile's halo is cut on all four sides.
test::SceneOptions noisy_window() {
  test::SceneOptions o;
  o.width = 160;
  o.height = 120;
  o.frames = 4;
  o.temporal = true;
  o.primal_sigma = 0.1f;
  o.gradient_sigma = 0.03f;
  o.variances = true;
  return o;
}

ReconSettings tiled_settings(ReconMethod method) {
  ReconSettings s;
  s.method = method;
  s.tile_size = 56;
  return s;
}

struct Agreement {
  double max_abs = 0, rel_mse_global = 0, rel_mse_per_pixel = 0;
};

Agreement compare(const ReconResult& tiled, const ReconResult& whole) {
  Agreement a;
  RelMseSums sums;
  for (size_t t = 0; t < whole.frames.size(); ++t) {
    for (size_t i = 0; i < whole.frames[t].data().size(); ++i)
      a.max_abs = std::max(a.max_abs, double(std::fabs(tiled.frames[t].data()[i] - whole.frames[t].data()[i])));
    sums.add(rel_mse_sums(tiled.frames[t], whole.frames[t]).value());
  }
  a.rel_mse_global = sums.global();
  a.rel_mse_per_pixel = sums.per_pixel();
  return a;
}

struct Solved {
  ReconResult tiled, whole;
  TileGrid grid;
};

Solved solve_both(const GradientWindow& w, const ReconSettings& s) {
  auto tiled = reconstruct_tiled(w, s);
  EXPECT_TRUE(tiled.ok()) << tiled.status().to_string();
  auto whole = reconstruct(w, s);
  EXPECT_TRUE(whole.ok()) << whole.status().to_string();
  auto grid = tile_grid_for(s, w.width(), w.height());
  EXPECT_TRUE(grid.ok());
  EXPECT_EQ(grid->count(), 9);
  return {std::move(tiled.value()), std::move(whole.value()), grid.value()};
}

TEST(TiledReconstructTest, L2AgreesWithWholeFrameSolve) {
  const GradientWindow w = test::make_window(noisy_window());
  const Solved r = solve_both(w, tiled_settings(ReconMethod::kL2));
  const Agreement a = compare(r.tiled, r.whole);
  EXPECT_LE(a.rel_mse_global, 1e-6);
  EXPECT_LE(a.rel_mse_per_pixel, 1e-6);
  EXPECT_LT(a.max_abs, 5e-3);
  for (const Image& f : r.tiled.frames) EXPECT_TRUE(test::all_finite(f));
}

TEST(TiledReconstructTest, TooSmallAHaloFailsTheBounds) {
  // The bounds above can fail: with a 2-pixel halo the cut boundary reaches
  // into the cores, and the seam metric sees the tile borders.
  ReconSettings s = tiled_settings(ReconMethod::kL2);
  s.tile_halo = 2;
  const Solved r = solve_both(test::make_window(noisy_window()), s);
  EXPECT_GT(compare(r.tiled, r.whole).rel_mse_global, 1e-6);
  const SeamMetric tiled = tile_seam_metric(r.tiled.frames[1], r.grid), whole = tile_seam_metric(r.whole.frames[1], r.grid);
  EXPECT_GT(std::fabs(tiled.border / whole.border - 1.0), 0.01);
}

TEST(TiledReconstructTest, L2AgreesToTheHaloTruncationWhenConverged) {
  // With CG run to 1e-7 both solves are near-exact: what remains is the
  // truncation at the halo, which the impulse response bounds.
  ReconSettings s = tiled_settings(ReconMethod::kL2);
  s.l2_tolerance = 1e-7;
  s.l2_max_iterations = 2000;
  const Solved r = solve_both(test::make_window(noisy_window()), s);
  const Agreement a = compare(r.tiled, r.whole);
  EXPECT_LE(a.rel_mse_global, 1e-10);
  EXPECT_LT(a.max_abs, 1e-4);
}

TEST(TiledReconstructTest, L1AgreesWithinSolverTolerance) {
  const GradientWindow w = test::make_window(noisy_window());
  const Solved r = solve_both(w, tiled_settings(ReconMethod::kL1));
  const Agreement a = compare(r.tiled, r.whole);
  // IRLS stops after a fixed schedule of inexact inner solves (inner
  // tolerance 1e-3), so two runs on different domains agree only to that
  // order: relative errors of ~1e-3 give a relMSE of ~1e-6.
  EXPECT_LE(a.rel_mse_global, 1e-5);
  EXPECT_LT(a.max_abs, 0.05);
  for (const Image& f : r.tiled.frames) EXPECT_TRUE(test::all_finite(f));
}

// A denoised data term's trust map (GradientFrame::data_weight) goes with
// each tile: a tiled solve that dropped it would weigh the primal by α alone
// and land far from the whole-frame solve, which the map moves.
TEST(TiledReconstructTest, TheDataTermsTrustMapIsCroppedWithTheTiles) {
  GradientWindow w = test::make_window(noisy_window());
  GradientWindow mapped;
  for (size_t t = 0; t < w.frames.size(); ++t) {
    auto f = std::make_shared<GradientFrame>(*w.frames[t]);
    f->data_weight = Image(f->width(), f->height(), 1);
    for (int y = 0; y < f->height(); ++y)
      for (int x = 0; x < f->width(); ++x) f->data_weight.at(x, y, 0) = x < f->width() / 2 ? 20.0f : 1.0f;
    mapped.frames.push_back(std::move(f));
  }
  for (ReconMethod m : {ReconMethod::kL2, ReconMethod::kL1}) {
    const Solved with_map = solve_both(mapped, tiled_settings(m));
    const Agreement a = compare(with_map.tiled, with_map.whole);
    EXPECT_LE(a.rel_mse_global, 1e-5) << recon_method_name(m);
    auto without_map = reconstruct(w, tiled_settings(m));
    ASSERT_TRUE(without_map.ok());
    EXPECT_GT(compare(with_map.whole, without_map.value()).rel_mse_global, 100 * a.rel_mse_global)
        << recon_method_name(m) << ": the map must matter for this test to see it dropped";
  }
}

TEST(TiledReconstructTest, ControlVariatesAreExactWithTheirHalo) {
  // After k Jacobi sweeps a pixel depends only on pixels within k steps; the
  // halo of the control variates is at least cv_iterations.
  for (ReconMethod m : {ReconMethod::kUniform, ReconMethod::kWeighted}) {
    ReconSettings s = tiled_settings(m);
    s.cv_iterations = 20;
    s.tile_halo = 4;
    EXPECT_EQ(tile_halo_for(s), 20);
    const Solved r = solve_both(test::make_window(noisy_window()), s);
    const Agreement a = compare(r.tiled, r.whole);
    EXPECT_LE(a.max_abs, 1e-6) << recon_method_name(m);
  }
}

TEST(TiledReconstructTest, TileBordersShowNoSeam) {
  for (ReconMethod m : {ReconMethod::kL2, ReconMethod::kL1, ReconMethod::kWeighted}) {
    const Solved r = solve_both(test::make_window(noisy_window()), tiled_settings(m));
    for (size_t t = 0; t < r.whole.frames.size(); ++t) {
      const SeamMetric tiled = tile_seam_metric(r.tiled.frames[t], r.grid);
      const SeamMetric whole = tile_seam_metric(r.whole.frames[t], r.grid);
      ASSERT_GT(whole.border, 0);
      // The same curvature across the borders as the whole-frame solve has
      // at those pixels (a seam would add a step or kink there) ...
      EXPECT_NEAR(tiled.border / whole.border, 1.0, 0.01) << recon_method_name(m) << " frame " << t;
      // ... and the borders look like the rest of the tiled image.
      EXPECT_NEAR(tiled.ratio(), whole.ratio(), 0.01 * whole.ratio()) << recon_method_name(m) << " frame " << t;
    }
  }
}

TEST(TiledReconstructTest, SeamMetricSeesASeam) {
  // The metric must be able to fail: a step of 0.05 between two tiles.
  const GradientWindow w = test::make_window(noisy_window());
  const Solved r = solve_both(w, tiled_settings(ReconMethod::kL2));
  Image stepped = r.whole.frames[0];
  const int border = r.grid.tile(1).core.x0;
  for (int y = 0; y < stepped.height(); ++y)
    for (int x = border; x < stepped.width(); ++x)
      for (int c = 0; c < 3; ++c) stepped.at(x, y, c) += 0.05f;
  const SeamMetric seam = tile_seam_metric(stepped, r.grid), clean = tile_seam_metric(r.whole.frames[0], r.grid);
  EXPECT_GT(seam.border, 1.05 * clean.border);
}

TEST(TiledReconstructTest, OneTileIsTheWholeFrameSolveBitForBit) {
  const GradientWindow w = test::make_window(noisy_window());
  ReconSettings s = tiled_settings(ReconMethod::kL2);
  s.tile_size = 160;
  EXPECT_FALSE(solves_by_tiles(s, w.width(), w.height()));
  auto tiled = reconstruct_tiled(w, s);
  auto whole = reconstruct(w, s);
  ASSERT_TRUE(tiled.ok() && whole.ok());
  for (size_t t = 0; t < whole->frames.size(); ++t) EXPECT_EQ(tiled->frames[t].data(), whole->frames[t].data());
}

TEST(TiledReconstructTest, DroppedConstraintsAreCountedOncePerPixel) {
  GradientWindow w = test::make_window(noisy_window());
  // NaNs in the halo overlaps and a masked dt column crossing a border.
  for (int y = 0; y < 120; y += 7) test::mutable_frame(w, 1).buffer(Term::kDx).at(52 + y % 9, y, 1) = NAN;
  std::vector<uint8_t>& mask = test::mutable_frame(w, 0).mask(Term::kDt);
  mask.assign(size_t(160) * 120, 1);
  for (int y = 0; y < 120; ++y) mask[size_t(y) * 160 + 54] = 0;
  const ReconSettings s = tiled_settings(ReconMethod::kL2);
  auto tiled = reconstruct_tiled(w, s);
  auto whole = reconstruct(w, s);
  ASSERT_TRUE(tiled.ok() && whole.ok());
  EXPECT_GT(whole->stats.non_finite_constraints[term_index(Term::kDx)], 0);
  EXPECT_EQ(tiled->stats.non_finite_constraints, whole->stats.non_finite_constraints);
  EXPECT_EQ(tiled->stats.masked_constraints, whole->stats.masked_constraints);
  for (const Image& f : tiled->frames) EXPECT_TRUE(test::all_finite(f));
}

TEST(TiledReconstructTest, ATileSubsetFillsOnlyItsCores) {
  const GradientWindow w = test::make_window(noisy_window());
  const ReconSettings s = tiled_settings(ReconMethod::kL2);
  auto grid = tile_grid_for(s, w.width(), w.height());
  ASSERT_TRUE(grid.ok());
  auto part = reconstruct_tiled(
      grid.value(), w.size(), [&](const PixelRect& r) -> Expected<GradientWindow> { return crop_window(w, r); },
      [&](const GradientWindow& tile, const PixelRect& core) { return reconstruct(tile, s, core); }, {4});
  auto all = reconstruct_tiled(w, s);
  ASSERT_TRUE(part.ok() && all.ok());
  const PixelRect core = grid->tile(4).core;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) {
      const float got = part->frames[2].at(x, y, 0);
      if (core.contains(x, y)) ASSERT_EQ(got, all->frames[2].at(x, y, 0));
      else ASSERT_EQ(got, 0.0f);
    }
  auto bad = reconstruct_tiled(
      grid.value(), w.size(), [&](const PixelRect& r) -> Expected<GradientWindow> { return crop_window(w, r); },
      [&](const GradientWindow& tile, const PixelRect& core2) { return reconstruct(tile, s, core2); }, {9});
  EXPECT_NE(bad.status().message().find("tile 9"), std::string::npos);
}

// ---- The halo from the operator's impulse response ----

TEST(TiledReconstructTest, DefaultHaloCoversTheImpulseResponse) {
  // A T-GPT window of 20 frames, as gdvr-bench-recon --impulse measures it.
  const int halo = tile_halo_for(ReconSettings());
  EXPECT_EQ(halo, 32);  // at the default α = 0.2
  auto measured = impulse_response_by_distance(ReconSettings(), 2 * halo + 41, 20);
  ASSERT_TRUE(measured.ok()) << measured.status().to_string();
  const std::vector<double>& response = measured.value();
  // Decays like e^(−α r) (a decade every ln(10)/α ≈ 11.5 px at α = 0.2) ...
  EXPECT_LT(response[20], 0.1 * response[10]);
  // ... and is below 1e-4 of its peak at the default halo, which is not
  // oversized: at half of it the response is still above 1e-4.
  EXPECT_LT(response[size_t(halo)], 1e-4);
  EXPECT_GT(response[size_t(halo) / 2], 1e-4);
}

TEST(TiledReconstructTest, HaloFollowsAlpha) {
  // A weaker screening weight reaches further: the halo from α keeps the
  // impulse response below 1e-4 of its peak at its edge, and is not twice
  // what that needs, at both ends of the range users pick (α 0.1 and 1).
  for (double alpha : {0.1, 1.0}) {
    ReconSettings s;
    s.alpha = alpha;
    const int halo = tile_halo_for(s);
    EXPECT_EQ(halo, tile_halo_for_alpha(alpha));
    auto measured = impulse_response_by_distance(s, 2 * halo + 41, 20);
    ASSERT_TRUE(measured.ok()) << measured.status().to_string();
    const std::vector<double>& response = measured.value();
    EXPECT_LT(response[size_t(halo)], 1e-4) << "alpha " << alpha << " halo " << halo;
    EXPECT_GT(response[size_t(halo) / 2], 1e-4) << "alpha " << alpha << " halo " << halo;
  }
  // An explicit halo is used as given.
  ReconSettings s;
  s.alpha = 0.1;
  s.tile_halo = 16;
  EXPECT_EQ(tile_halo_for(s), 16);
  // A tiny α asks for more than any frame: the halo then covers the frame.
  EXPECT_GT(tile_halo_for_alpha(1e-12), 1 << 20);
}

}  // namespace
}  // namespace gdvr
