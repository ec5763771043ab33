// Equal-time ratios and the CSV/JSON forms of report rows.
#include "core/report/report_results.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

namespace gdvr {
namespace {

ReportRow row(const std::string& method, double budget, double seconds, double rel) {
  ReportRow r;
  r.method = method;
  r.integrator = method.substr(0, method.find('-'));
  r.budget_s = budget;
  r.seconds_per_frame = seconds;
  r.rel_mse_global = rel;
  r.rel_mse_per_pixel = 2 * rel;
  r.frames = 1;
  return r;
}

TEST(ReportResultsTest, EqualTimeRatiosComeFromPtAtTheSameBudget) {
  std::vector<ReportRow> rows = {row("pt", 1, 1.0, 0.1), row("gpt-l2", 1, 1.0, 0.05), row("pt", 4, 4.0, 0.025),
                                 row("gpt-l2", 4, 2.0, 0.01)};
  fill_equal_time_ratios(&rows);
  EXPECT_NEAR(rows[1].equal_time_ratio_global, 2.0, 1e-12);
  EXPECT_NEAR(rows[1].equal_time_ratio_per_pixel, 2.0, 1e-12);
  EXPECT_NEAR(rows[3].equal_time_ratio_global, 2.5, 1e-12);
  // Measured 2 s: PT's curve (1/t) gives 0.05 there -> 0.05 / 0.01.
  EXPECT_NEAR(rows[3].equal_time_ratio_interpolated, 5.0, 1e-9);
  EXPECT_NEAR(rows[0].equal_time_ratio_global, 1.0, 1e-12);
  // No PT at a budget: no ratio.
  std::vector<ReportRow> lone = {row("gpt-l1", 2, 2.0, 0.1)};
  fill_equal_time_ratios(&lone);
  EXPECT_TRUE(std::isnan(lone[0].equal_time_ratio_global));
  EXPECT_TRUE(std::isnan(lone[0].equal_time_ratio_interpolated));
}

TEST(ReportResultsTest, CsvHasOneLinePerRowAndEmptyFieldsForAbsentValues) {
  std::vector<ReportRow> rows = {row("pt", 0.5, 0.51, 0.2), row("gpt-l2", 0.5, 0.6, 0.1)};
  rows[1].flicker = 0.003;
  const std::string csv = results_csv(rows);
  std::istringstream in(csv);
  std::string header, l1, l2, extra;
  std::getline(in, header);
  std::getline(in, l1);
  std::getline(in, l2);
  EXPECT_FALSE(std::getline(in, extra));
  auto count = [](const std::string& s) { return std::count(s.begin(), s.end(), ','); };
  EXPECT_EQ(count(header), count(l1));
  EXPECT_EQ(count(header), count(l2));
  EXPECT_EQ(header.rfind("method,integrator,", 0), 0u);
  EXPECT_EQ(l1.rfind("pt,pt,,0.5,1,0.51,", 0), 0u) << l1;
  EXPECT_NE(l1.find(",,"), std::string::npos);  // flicker absent
  EXPECT_NE(l2.find("0.003"), std::string::npos);
  EXPECT_EQ(l1.find("nan"), std::string::npos);
}

TEST(ReportResultsTest, JsonCarriesMetaRowsAndNullForAbsentValues) {
  ReportMeta meta;
  meta.input = "scene.xml";
  meta.reference_spp = 64;
  meta.load = "1.00 0.50 0.25";
  std::vector<ReportRow> rows = {row("pt", 1, 1.0, 0.1)};
  rows[0].left_out["gradient sampling and reconstruction: integrator pt"] = 1;
  rows[0].frame_rel_mse_global = {0.1};
  auto j = nlohmann::json::parse(results_json(meta, rows));
  EXPECT_EQ(j["input"], "scene.xml");
  EXPECT_EQ(j["reference"]["spp"], 64);
  EXPECT_EQ(j["machine"]["loadavg"], "1.00 0.50 0.25");
  ASSERT_EQ(j["rows"].size(), 1u);
  EXPECT_DOUBLE_EQ(j["rows"][0]["rel_mse_global"].get<double>(), 0.1);
  EXPECT_TRUE(j["rows"][0]["flicker"].is_null());
  EXPECT_EQ(j["rows"][0]["left_out"]["gradient sampling and reconstruction: integrator pt"], 1);
}

}  // namespace
}  // namespace gdvr
