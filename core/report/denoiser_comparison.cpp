#include "core/report/denoiser_comparison.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace gdvr {
namespace {

bool is_denoised_baseline(const ReportRow& r) { return r.method == "pt-oidn" || r.method == "pt-sd-oidn"; }
bool is_gradient_domain(const ReportRow& r) { return r.integrator == "gpt" || r.integrator == "tgpt"; }

double ratio(double num, double den) {
  return std::isfinite(num) && std::isfinite(den) && den > 0 ? num / den : kNoValue;
}

// The floor is well below a figure when it is at most `fraction` of it; an
// unknown floor or figure never is.
bool floor_below(double floor, double figure, double fraction) {
  return std::isfinite(floor) && std::isfinite(figure) && floor <= fraction * figure;
}

// max(figure − floor, 0) / (baseline − floor), where the floor is known and
// at most `fraction` of the baseline's figure.
double floor_removed_ratio(double figure, double baseline, double floor, double fraction) {
  if (!std::isfinite(figure) || !std::isfinite(baseline) || !std::isfinite(floor) || floor > fraction * baseline)
    return kNoValue;
  return ratio(std::max(figure - floor, 0.0), baseline - floor);
}

std::string number(double v, const char* f) {
  if (!std::isfinite(v)) return "–";
  char buf[40];
  std::snprintf(buf, sizeof(buf), f, v);
  return buf;
}

}  // namespace

std::vector<DenoiserComparison> compare_with_denoisers(const std::vector<ReportRow>& rows,
                                                       const ReferenceNoiseFloor& floor,
                                                       const DenoiserTargets& targets) {
  std::vector<DenoiserComparison> out;
  for (const ReportRow& r : rows) {
    if (!is_gradient_domain(r)) continue;
    // The strictest baseline: each figure against the better denoised row of the budget.
    double best_pp = kNoValue, best_flicker = kNoValue, best_global = kNoValue, fastest = kNoValue;
    std::string baseline;
    auto lower = [](double cur, double v) { return !std::isfinite(cur) || (std::isfinite(v) && v < cur) ? v : cur; };
    for (const ReportRow& b : rows) {
      if (!is_denoised_baseline(b) || b.budget_s != r.budget_s) continue;
      if (!std::isfinite(best_pp) || (std::isfinite(b.rel_mse_per_pixel) && b.rel_mse_per_pixel < best_pp))
        baseline = b.method;
      best_pp = lower(best_pp, b.rel_mse_per_pixel);
      best_flicker = lower(best_flicker, b.flicker);
      best_global = lower(best_global, b.rel_mse_global);
      fastest = lower(fastest, b.seconds_per_frame);
    }
    if (baseline.empty()) continue;
    DenoiserComparison c;
    c.method = r.method;
    c.budget_s = r.budget_s;
    c.baseline = baseline;
    c.seconds_ratio = ratio(r.seconds_per_frame, fastest);
    c.ratio_per_pixel = ratio(r.rel_mse_per_pixel, best_pp);
    c.ratio_global = ratio(r.rel_mse_global, best_global);
    const bool animated = std::isfinite(r.flicker) && std::isfinite(best_flicker);
    c.ratio_flicker = animated ? ratio(r.flicker, best_flicker) : kNoValue;
    c.meets_per_pixel = std::isfinite(c.ratio_per_pixel) && c.ratio_per_pixel <= targets.per_pixel;
    c.meets_global = std::isfinite(c.ratio_global) && c.ratio_global <= targets.global;
    c.meets_flicker = animated ? std::isfinite(c.ratio_flicker) && c.ratio_flicker <= targets.flicker : true;
    // Faster than the baseline only handicaps the method; slower must stay within the tolerance.
    c.equal_time = std::isfinite(c.seconds_ratio) && c.seconds_ratio <= 1.0 + targets.time_tolerance;
    const double keep = targets.removable_floor_fraction;
    c.floor_removed_per_pixel = floor_removed_ratio(r.rel_mse_per_pixel, best_pp, floor.per_pixel, keep);
    c.floor_removed_global = floor_removed_ratio(r.rel_mse_global, best_global, floor.global, keep);
    if (animated) c.floor_removed_flicker = floor_removed_ratio(r.flicker, best_flicker, floor.flicker, keep);
    const double f = targets.floor_fraction;
    c.floor_well_below = floor_below(floor.per_pixel, std::min(r.rel_mse_per_pixel, best_pp), f) &&
                         floor_below(floor.global, std::min(r.rel_mse_global, best_global), f) &&
                         (!animated || floor_below(floor.flicker, std::min(r.flicker, best_flicker), f));
    out.push_back(c);
  }
  return out;
}

std::string denoiser_comparison_markdown(const std::vector<DenoiserComparison>& rows,
                                         const ReferenceNoiseFloor& floor, const DenoiserTargets& targets) {
  if (rows.empty()) return "";
  std::ostringstream o;
  auto mark = [](bool ok) { return ok ? " ✓" : " ✗"; };
  o << "Against the best denoised path tracing (method / baseline; targets: per-pixel ≤ "
    << number(targets.per_pixel, "%g") << "×, flicker ≤ " << number(targets.flicker, "%g") << "×, global ≤ "
    << number(targets.global, "%g") << "×, time ≤ " << number(1 + targets.time_tolerance, "%g") << "×)\n\n";
  o << "| method | budget s | baseline | time | per-pixel | flicker | global | reference floor | verdict | floor removed: "
       "per-pixel / flicker / global |\n";
  o << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const DenoiserComparison& c : rows) {
    o << "| " << c.method << " | " << number(c.budget_s, "%g") << " | " << c.baseline << " | "
      << number(c.seconds_ratio, "%.2f") << mark(c.equal_time) << " | " << number(c.ratio_per_pixel, "%.2f")
      << mark(c.meets_per_pixel) << " | " << number(c.ratio_flicker, "%.2f") << mark(c.meets_flicker) << " | "
      << number(c.ratio_global, "%.2f") << mark(c.meets_global) << " | "
      << (c.floor_well_below ? "well below" : "too close") << " | " << (c.meets_all() ? "meets" : "misses") << " | "
      << number(c.floor_removed_per_pixel, "%.2f") << " / " << number(c.floor_removed_flicker, "%.2f") << " / "
      << number(c.floor_removed_global, "%.2f") << " |\n";
  }
  o << "\nReference noise floor (what its own noise adds to each figure): per-pixel "
    << number(floor.per_pixel, "%.3g") << ", flicker " << number(floor.flicker, "%.3g") << ", global "
    << number(floor.global, "%.3g") << "; \"well below\" means at most " << number(targets.floor_fraction, "%g")
    << "× every figure compared. The floor-removed ratios take it off both figures (an estimate, given where it is "
       "at most "
    << number(targets.removable_floor_fraction, "%g") << "× the baseline's figure; not a verdict).\n";
  return o.str();
}

}  // namespace gdvr
