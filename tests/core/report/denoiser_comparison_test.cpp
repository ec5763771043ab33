#include "core/report/denoiser_comparison.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gdvr {
namespace {

ReportRow row(const std::string& method, const std::string& integrator, double budget, double seconds, double pp,
              double flicker, double global) {
  ReportRow r;
  r.method = method;
  r.integrator = integrator;
  r.budget_s = budget;
  r.seconds_per_frame = seconds;
  r.rel_mse_per_pixel = pp;
  r.flicker = flicker;
  r.rel_mse_global = global;
  return r;
}

ReferenceNoiseFloor tiny_floor() { return {1e-9, 1e-9, 1e-9}; }

TEST(DenoiserComparisonTest, EachFigureAgainstTheBetterDenoisedBaseline) {
  const std::vector<ReportRow> rows = {
      row("pt", "pt", 1, 1.0, 1e-2, 1e-2, 1e-2),
      row("pt-oidn", "pt", 1, 1.0, 8e-4, 4e-3, 3e-3),     // better flicker than pt-sd-oidn? no: worse
      row("pt-sd-oidn", "pt", 1, 0.98, 6e-4, 8e-4, 7e-4),  // best per-pixel, flicker and global
      row("tgpt-l1", "tgpt", 1, 1.02, 2.4e-4, 1e-4, 5e-4),
  };
  auto c = compare_with_denoisers(rows, tiny_floor());
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].method, "tgpt-l1");
  EXPECT_EQ(c[0].baseline, "pt-sd-oidn");
  EXPECT_NEAR(c[0].ratio_per_pixel, 0.4, 1e-9);
  EXPECT_NEAR(c[0].ratio_flicker, 0.125, 1e-9);
  EXPECT_NEAR(c[0].ratio_global, 5.0 / 7.0, 1e-9);
  EXPECT_NEAR(c[0].seconds_ratio, 1.02 / 0.98, 1e-9);  // against the faster baseline
  EXPECT_TRUE(c[0].equal_time);
  EXPECT_TRUE(c[0].floor_well_below);
  EXPECT_TRUE(c[0].meets_all());
}

TEST(DenoiserComparisonTest, EachConditionCanFailOnItsOwn) {
  const ReportRow base = row("pt-sd-oidn", "pt", 0.5, 1.0, 1e-3, 1e-3, 1e-3);
  auto verdict = [&](ReportRow method, ReferenceNoiseFloor floor) {
    auto c = compare_with_denoisers({base, method}, floor);
    EXPECT_EQ(c.size(), 1u);
    return c.empty() ? DenoiserComparison{} : c[0];
  };
  const ReportRow good = row("tgpt-l2", "tgpt", 0.5, 1.0, 4e-4, 1e-4, 9e-4);
  EXPECT_TRUE(verdict(good, tiny_floor()).meets_all());
  ReportRow r = good;
  r.rel_mse_per_pixel = 6e-4;  // 0.6×: not half
  EXPECT_FALSE(verdict(r, tiny_floor()).meets_per_pixel);
  r = good;
  r.flicker = 3e-4;  // 0.3×
  EXPECT_FALSE(verdict(r, tiny_floor()).meets_flicker);
  r = good;
  r.rel_mse_global = 1.1e-3;  // fireflies spread: worse than the denoiser
  EXPECT_FALSE(verdict(r, tiny_floor()).meets_global);
  r = good;
  r.seconds_per_frame = 1.06;  // 6 % slower than the baseline
  auto slow = verdict(r, tiny_floor());
  EXPECT_FALSE(slow.equal_time);
  EXPECT_FALSE(slow.meets_all());
  r.seconds_per_frame = 0.5;  // faster is fine
  EXPECT_TRUE(verdict(r, tiny_floor()).equal_time);
  // A reference whose own flicker is a third of the method's cannot judge it.
  auto noisy_ref = verdict(good, {1e-9, 1e-9, 3e-5});
  EXPECT_FALSE(noisy_ref.floor_well_below);
  EXPECT_FALSE(noisy_ref.meets_all());
  // Unknown floor: no verdict either.
  EXPECT_FALSE(verdict(good, ReferenceNoiseFloor{}).floor_well_below);
}

// A reference too noisy to judge still gives an estimate: its floor, which
// adds to every figure, taken off both; none where it is most of the
// baseline's figure.
TEST(DenoiserComparisonTest, TheFloorRemovedRatiosTakeTheReferenceNoiseOffBothFigures) {
  const std::vector<ReportRow> rows = {row("pt-sd-oidn", "pt", 1, 1.0, 6e-4, 1e-4, 2e-3),
                                       row("tgpt-l1", "tgpt", 1, 1.0, 9e-4, 2e-5, 2.1e-3)};
  const ReferenceNoiseFloor floor{1.9e-3, 2.4e-4, 1e-5};  // global, per-pixel, flicker
  auto c = compare_with_denoisers(rows, floor);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_FALSE(c[0].floor_well_below);
  EXPECT_FALSE(c[0].meets_all());
  EXPECT_NEAR(c[0].ratio_per_pixel, 1.5, 1e-9);
  EXPECT_NEAR(c[0].floor_removed_per_pixel, (9e-4 - 2.4e-4) / (6e-4 - 2.4e-4), 1e-9);  // 1.83
  EXPECT_NEAR(c[0].floor_removed_flicker, (2e-5 - 1e-5) / (1e-4 - 1e-5), 1e-9);
  EXPECT_FALSE(std::isfinite(c[0].floor_removed_global)) << "the floor is 95 % of the baseline's global figure";
  // A method at the floor: nothing of its own error is left to see.
  const std::vector<ReportRow> at_floor = {rows[0], row("tgpt-l1", "tgpt", 1, 1.0, 2e-4, 2e-5, 2.1e-3)};
  EXPECT_EQ(compare_with_denoisers(at_floor, floor)[0].floor_removed_per_pixel, 0.0);
  // Unknown floor: no estimate.
  EXPECT_FALSE(std::isfinite(compare_with_denoisers(rows, ReferenceNoiseFloor{})[0].floor_removed_per_pixel));
  const std::string md = denoiser_comparison_markdown(c, floor);
  EXPECT_NE(md.find("| 1.83 / 0.11 / – |"), std::string::npos) << md;
}

TEST(DenoiserComparisonTest, NothingToCompareWithoutADenoisedBaselineAtThatBudget) {
  const std::vector<ReportRow> rows = {row("pt", "pt", 1, 1, 1e-2, 1e-2, 1e-2),
                                       row("pt-sd-oidn", "pt", 2, 2, 1e-3, 1e-3, 1e-3),
                                       row("tgpt-l1", "tgpt", 1, 1, 1e-4, 1e-4, 1e-4)};
  EXPECT_TRUE(compare_with_denoisers(rows, tiny_floor()).empty());
  EXPECT_EQ(denoiser_comparison_markdown({}, tiny_floor()), "");
}

TEST(DenoiserComparisonTest, AStillHasNoFlickerToMeet) {
  const double none = kNoValue;
  const std::vector<ReportRow> rows = {row("pt-oidn", "pt", 1, 1, 1e-3, none, 1e-3),
                                       row("gpt-l1", "gpt", 1, 1, 4e-4, none, 5e-4)};
  auto c = compare_with_denoisers(rows, {1e-9, 1e-9, kNoValue});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_TRUE(c[0].meets_flicker);
  EXPECT_TRUE(c[0].floor_well_below);
  EXPECT_TRUE(c[0].meets_all());
  const std::string md = denoiser_comparison_markdown(c, {1e-9, 1e-9, kNoValue});
  EXPECT_NE(md.find("| gpt-l1 | 1 | pt-oidn |"), std::string::npos) << md;
  EXPECT_NE(md.find("meets"), std::string::npos);
}

}  // namespace
}  // namespace gdvr
