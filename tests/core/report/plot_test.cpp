// The report's built-in plot renderer: axes, ticks, series pixels, heat maps.
#include "core/report/plot.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gdvr {
namespace {

bool has_color(const Image& im, Rgb c) {
  for (int y = 0; y < im.height(); ++y)
    for (int x = 0; x < im.width(); ++x) {
      Rgb p = im.rgb(x, y);
      if (std::abs(p.r - c.r) < 1e-4f && std::abs(p.g - c.g) < 1e-4f && std::abs(p.b - c.b) < 1e-4f) return true;
    }
  return false;
}

TEST(ReportPlotTest, LogAxisTicksAreDecadesInsideTheRange) {
  PlotAxis a = plot_axis({0.001, 0.5, 2.0, -1.0, NAN}, /* log_scale = */ true);
  EXPECT_LT(a.lo, std::log10(0.001));
  EXPECT_GT(a.hi, std::log10(2.0));
  ASSERT_GE(a.ticks.size(), 3u);
  for (double t : a.ticks) {
    EXPECT_GE(std::log10(t), a.lo);
    EXPECT_LE(std::log10(t), a.hi);
  }
  EXPECT_NE(std::find(a.ticks.begin(), a.ticks.end(), 0.01), a.ticks.end());
  // A narrow range still gets ticks (1, 2, 5 or 1..9 multiples).
  PlotAxis n = plot_axis({0.3, 0.4}, true);
  EXPECT_GE(n.ticks.size(), 1u);
  // One value: a decade around it.
  PlotAxis one = plot_axis({1.0}, true);
  EXPECT_LT(one.lo, 0.0);
  EXPECT_GT(one.hi, 0.0);
  PlotAxis lin = plot_axis({0.0, 10.0}, false);
  EXPECT_GE(lin.ticks.size(), 3u);
}

TEST(ReportPlotTest, TickLabelsAreShort) {
  EXPECT_EQ(tick_label(1e-5), "1e-5");
  EXPECT_EQ(tick_label(0.01), "0.01");
  EXPECT_EQ(tick_label(2e6), "2e6");
  EXPECT_EQ(tick_label(5), "5");
}

TEST(ReportPlotTest, SeriesAreDrawnInTheirColours) {
  PlotSeries a{"pt", plot_color(1), {{0.5, 0.1}, {1, 0.05}, {2, 0.025}}};
  PlotSeries b{"gpt", plot_color(2), {{0.5, 0.05}, {1, 0.02}, {2, NAN}, {-1, 0.3}}};
  PlotOptions o;
  o.width = 320;
  o.height = 200;
  Image im = render_plot({a, b}, o);
  ASSERT_EQ(im.width(), 320);
  ASSERT_EQ(im.height(), 200);
  ASSERT_EQ(im.channels(), 3);
  EXPECT_TRUE(has_color(im, plot_color(1)));
  EXPECT_TRUE(has_color(im, plot_color(2)));
  EXPECT_FALSE(has_color(im, plot_color(3)));
  for (float v : im.data()) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
  // Empty input: axes only, still a valid image.
  Image empty = render_plot({}, o);
  EXPECT_EQ(empty.width(), 320);
  EXPECT_FALSE(has_color(empty, plot_color(1)));
}

TEST(ReportPlotTest, HeatMapRampAndNonFinite) {
  Image rate(4, 1, 1);
  rate.at(0, 0, 0) = 0.0f;
  rate.at(1, 0, 0) = 1.0f;
  rate.at(2, 0, 0) = 1.0f / 3.0f;
  rate.at(3, 0, 0) = std::nanf("");
  Image h = heat_map(rate);
  EXPECT_EQ(h.rgb(0, 0).r, 0.0f);
  EXPECT_EQ(h.rgb(1, 0).b, 1.0f);
  EXPECT_NEAR(h.rgb(2, 0).r, 1.0f, 1e-6);
  EXPECT_NEAR(h.rgb(2, 0).g, 0.0f, 1e-6);
  EXPECT_GT(h.rgb(3, 0).b, h.rgb(3, 0).r);
  EXPECT_EQ(css_color({1.0f, 0.0f, 0.5f}), "#ff0080");
}

}  // namespace
}  // namespace gdvr
