// A minimal line-plot renderer for the error-vs-time report: gdvr has no
// plotting library among its dependencies, so plots are drawn straight into a
// display-encoded Image (white background, [0, 1] RGB) for write_png8. Tick
// labels use a built-in 3x5 digit font; titles and the legend belong to the
// HTML around the image (series colours come from plot_color()).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/image/image.h"

namespace gdvr {

struct PlotSeries {
  std::string name;
  Rgb color{0, 0, 0};
  std::vector<std::pair<double, double>> points;  // (x, y); non-finite (and, on log axes, non-positive) are skipped
};

struct PlotOptions {
  int width = 640;
  int height = 420;
  bool log_x = true;
  bool log_y = true;
};

// The axis range and ticks a plot uses (exposed for tests).
struct PlotAxis {
  double lo = 0, hi = 1;       // in plot units (log10 of the value on log axes)
  std::vector<double> ticks;   // values (not log) inside [lo, hi]
};
PlotAxis plot_axis(const std::vector<double>& values, bool log_scale);

// Renders the series; an empty or all-invalid input gives axes only.
Image render_plot(const std::vector<PlotSeries>& series, const PlotOptions& options);

// The i-th colour of a fixed, colour-blind-friendly palette (Okabe–Ito), as
// display values in [0, 1].
Rgb plot_color(int index);
// "#rrggbb" of a display colour, for the HTML legend.
std::string css_color(Rgb c);

// Rate map in [0, 1] (channel 0) -> display RGB (black, red, yellow, white);
// non-finite values show as blue so they stand out.
Image heat_map(const Image& rate);

// Tick label text: "%g" made short ("1e-05" -> "1e-5").
std::string tick_label(double value);

}  // namespace gdvr
