#include "core/report/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace gdvr {
namespace {

// 3x5 glyphs, one row per 3 bits (top row first, leftmost pixel = bit 2).
struct Glyph {
  char c;
  unsigned char rows[5];
};
constexpr Glyph kFont[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
    {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}},
    {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}}, {'.', {0, 0, 0, 0, 2}}, {'-', {0, 0, 7, 0, 0}},
    {'+', {0, 2, 7, 2, 0}}, {'e', {0, 7, 7, 4, 7}},
};

class Canvas {
 public:
  explicit Canvas(Image* im) : im_(im) {}
  void set(int x, int y, Rgb c) {
    if (x >= 0 && y >= 0 && x < im_->width() && y < im_->height()) im_->set_rgb(x, y, c);
  }
  void fill(int x0, int y0, int x1, int y1, Rgb c) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) set(x, y, c);
  }
  // Bresenham, `thick` pixels wide (a square brush).
  void line(int x0, int y0, int x1, int y1, Rgb c, int thick) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    const int lo = -(thick - 1) / 2, hi = thick / 2;
    for (int guard = 0; guard < 100000; ++guard) {
      fill(x0 + lo, y0 + lo, x0 + hi, y0 + hi, c);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) err += dy, x0 += sx;
      if (e2 <= dx) err += dx, y0 += sy;
    }
  }
  // Text at scale `s` with its top-left corner at (x, y); returns the width.
  int text(int x, int y, const std::string& s, Rgb c, int scale) {
    int cx = x;
    for (char ch : s) {
      for (const Glyph& g : kFont)
        if (g.c == ch)
          for (int r = 0; r < 5; ++r)
            for (int b = 0; b < 3; ++b)
              if (g.rows[r] & (4 >> b)) fill(cx + b * scale, y + r * scale, cx + b * scale + scale - 1, y + r * scale + scale - 1, c);
      cx += 4 * scale;
    }
    return cx - x - scale;
  }
  static int text_width(const std::string& s, int scale) { return s.empty() ? 0 : int(s.size()) * 4 * scale - scale; }

 private:
  Image* im_;
};

bool usable(double v, bool log_scale) { return std::isfinite(v) && (!log_scale || v > 0); }
double to_axis(double v, bool log_scale) { return log_scale ? std::log10(v) : v; }

}  // namespace

std::string tick_label(double value) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", value);
  std::string s = buf;
  // "1e-05" -> "1e-5", "1e+06" -> "1e6"
  size_t e = s.find('e');
  if (e != std::string::npos) {
    std::string mant = s.substr(0, e), ex = s.substr(e + 1);
    std::string sign;
    if (!ex.empty() && (ex[0] == '-' || ex[0] == '+')) {
      if (ex[0] == '-') sign = "-";
      ex = ex.substr(1);
    }
    while (ex.size() > 1 && ex[0] == '0') ex = ex.substr(1);
    s = mant + "e" + sign + ex;
  }
  return s;
}

PlotAxis plot_axis(const std::vector<double>& values, bool log_scale) {
  PlotAxis axis;
  double lo = INFINITY, hi = -INFINITY;
  for (double v : values)
    if (usable(v, log_scale)) {
      lo = std::min(lo, to_axis(v, log_scale));
      hi = std::max(hi, to_axis(v, log_scale));
    }
  if (!(lo <= hi)) {
    lo = log_scale ? -1 : 0;
    hi = log_scale ? 0 : 1;
  }
  if (hi - lo < 1e-9) {  // one value: a decade (log) or ±1 (linear) around it
    const double pad = log_scale ? 0.5 : std::max(1.0, std::abs(lo) * 0.5);
    lo -= pad, hi += pad;
  }
  const double margin = 0.06 * (hi - lo);
  axis.lo = lo - margin;
  axis.hi = hi + margin;
  if (log_scale) {
    for (const std::vector<int>& mults : {std::vector<int>{1}, std::vector<int>{1, 2, 5}, std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9}}) {
      axis.ticks.clear();
      for (int d = int(std::floor(axis.lo)) - 1; d <= int(std::ceil(axis.hi)); ++d)
        for (int m : mults) {
          const double v = m * std::pow(10.0, d);
          if (std::log10(v) >= axis.lo && std::log10(v) <= axis.hi) axis.ticks.push_back(v);
        }
      if (axis.ticks.size() >= 3) break;
    }
    if (axis.ticks.size() > 12) {  // many decades: every n-th decade
      std::vector<double> thin;
      const size_t step = (axis.ticks.size() + 9) / 10;
      for (size_t i = 0; i < axis.ticks.size(); i += step) thin.push_back(axis.ticks[i]);
      axis.ticks = thin;
    }
  } else {
    const double raw = (axis.hi - axis.lo) / 6;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = mag;
    for (double m : {1.0, 2.0, 5.0, 10.0})
      if (m * mag >= raw) {
        step = m * mag;
        break;
      }
    for (double v = std::ceil(axis.lo / step) * step; v <= axis.hi + 1e-12; v += step)
      axis.ticks.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  }
  return axis;
}

Rgb plot_color(int index) {
  static const Rgb kPalette[] = {{0.0f, 0.0f, 0.0f},       {0.902f, 0.624f, 0.0f}, {0.337f, 0.706f, 0.914f},
                                 {0.0f, 0.620f, 0.451f},   {0.800f, 0.475f, 0.655f}, {0.835f, 0.369f, 0.0f},
                                 {0.0f, 0.447f, 0.698f},   {0.941f, 0.894f, 0.259f}};
  const int n = int(sizeof(kPalette) / sizeof(kPalette[0]));
  return kPalette[((index % n) + n) % n];
}

std::string css_color(Rgb c) {
  auto q = [](float v) { return int(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
  char buf[16];
  std::snprintf(buf, sizeof(buf), "#%02x%02x%02x", q(c.r), q(c.g), q(c.b));
  return buf;
}

Image render_plot(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  const int w = std::max(options.width, 120), h = std::max(options.height, 100);
  Image im(w, h, 3);
  std::fill(im.data().begin(), im.data().end(), 1.0f);
  Canvas cv(&im);
  std::vector<double> xs, ys;
  for (const PlotSeries& s : series)
    for (const auto& [x, y] : s.points)
      if (usable(x, options.log_x) && usable(y, options.log_y)) xs.push_back(x), ys.push_back(y);
  const PlotAxis ax = plot_axis(xs, options.log_x), ay = plot_axis(ys, options.log_y);

  const int scale = 2;
  int label_w = 0;
  for (double t : ay.ticks) label_w = std::max(label_w, Canvas::text_width(tick_label(t), scale));
  const int left = label_w + 16, right = w - 12, top = 10, bottom = h - 5 * scale - 16;
  auto px = [&](double x) {
    return left + int(std::lround((to_axis(x, options.log_x) - ax.lo) / (ax.hi - ax.lo) * (right - left)));
  };
  auto py = [&](double y) {
    return bottom - int(std::lround((to_axis(y, options.log_y) - ay.lo) / (ay.hi - ay.lo) * (bottom - top)));
  };
  const Rgb grid{0.88f, 0.88f, 0.88f}, axis_c{0.1f, 0.1f, 0.1f};
  // ---- Grid and tick labels ----
  // Labels that would overlap the previous one are left out (the grid line stays).
  int last_label_end = -1000000;
  for (double t : ax.ticks) {
    const int x = px(t);
    cv.line(x, top, x, bottom, grid, 1);
    cv.line(x, bottom, x, bottom + 4, axis_c, 1);
    const std::string l = tick_label(t);
    const int x0 = x - Canvas::text_width(l, scale) / 2;
    if (x0 < last_label_end + 3 * scale) continue;
    last_label_end = x0 + cv.text(x0, bottom + 8, l, axis_c, scale);
  }
  int last_label_top = 1000000;
  for (double t : ay.ticks) {
    const int y = py(t);
    cv.line(left, y, right, y, grid, 1);
    cv.line(left - 4, y, left, y, axis_c, 1);
    const std::string l = tick_label(t);
    const int y0 = y - 5 * scale / 2;
    if (y0 + 5 * scale + 2 * scale > last_label_top) continue;
    cv.text(left - 7 - Canvas::text_width(l, scale), y0, l, axis_c, scale);
    last_label_top = y0;
  }
  cv.line(left, top, left, bottom, axis_c, 1);
  cv.line(left, bottom, right, bottom, axis_c, 1);
  // ---- Series: lines through the points sorted by x, square markers ----
  for (const PlotSeries& s : series) {
    std::vector<std::pair<double, double>> pts;
    for (const auto& p : s.points)
      if (usable(p.first, options.log_x) && usable(p.second, options.log_y)) pts.push_back(p);
    std::sort(pts.begin(), pts.end());
    for (size_t i = 0; i + 1 < pts.size(); ++i)
      cv.line(px(pts[i].first), py(pts[i].second), px(pts[i + 1].first), py(pts[i + 1].second), s.color, 2);
    for (const auto& p : pts) cv.fill(px(p.first) - 3, py(p.second) - 3, px(p.first) + 3, py(p.second) + 3, s.color);
  }
  return im;
}

Image heat_map(const Image& rate) {
  Image out(rate.width(), rate.height(), 3);
  if (rate.channels() < 1) return out;
  for (int y = 0; y < rate.height(); ++y)
    for (int x = 0; x < rate.width(); ++x) {
      const float v = rate.at(x, y, 0);
      if (!std::isfinite(v)) {
        out.set_rgb(x, y, {0.2f, 0.4f, 1.0f});
        continue;
      }
      const float t = std::clamp(v, 0.0f, 1.0f) * 3.0f;  // black -> red -> yellow -> white
      out.set_rgb(x, y, {std::min(t, 1.0f), std::clamp(t - 1.0f, 0.0f, 1.0f), std::clamp(t - 2.0f, 0.0f, 1.0f)});
    }
  return out;
}

}  // namespace gdvr
