// The comparison users make before they switch renderers (docs/report.md,
// "Against the denoiser"): at equal wall time per frame, each gradient-domain
// method against the best path tracing + denoiser baseline of the same budget
// (the better of pt-oidn and pt-sd-oidn, OIDN guided by albedo and normal).
//
// gdvr's targets, per budget: per-pixel relMSE ≤ 0.5× the baseline's,
// flicker ≤ 0.2×, global relMSE ≤ 1× (no fireflies spread by the solve).
// A verdict counts only if both rows took about the same time (the budget is
// the user's wait per frame) and the reference's own noise is well below every
// figure it compares; otherwise the row says which condition failed.
#pragma once

#include <string>
#include <vector>

#include "core/report/report_results.h"

namespace gdvr {

struct DenoiserTargets {
  double per_pixel = 0.5;  // method / baseline, at most
  double flicker = 0.2;
  double global = 1.0;
  // Equal time: the method's seconds per frame within this factor of the baseline's.
  double time_tolerance = 0.05;
  // "Well below": the reference's floor at most this fraction of every figure compared.
  double floor_fraction = 0.1;
  // The floor-removed ratios are given where the floor is at most this
  // fraction of the baseline's figure (above it they are mostly noise).
  double removable_floor_fraction = 0.5;
};

struct DenoiserComparison {
  std::string method;    // a gradient-domain row (gpt-*, tgpt-*)
  double budget_s = 0;
  std::string baseline;  // pt-oidn or pt-sd-oidn: the lower per-pixel relMSE at this budget
  double seconds_ratio = kNoValue;  // method's seconds per frame / baseline's
  double ratio_per_pixel = kNoValue, ratio_flicker = kNoValue, ratio_global = kNoValue;  // method / baseline
  bool meets_per_pixel = false, meets_flicker = false, meets_global = false;
  bool equal_time = false;        // seconds_ratio within 1 ± time_tolerance
  bool floor_well_below = false;  // the reference floor ≤ floor_fraction of each compared figure (unknown: false)
  // An estimate for rows whose reference is too noisy to judge: the floor is
  // what the reference's own noise adds to every figure (in expectation, as
  // it is independent of the method's error), so it is taken off both:
  // max(method − floor, 0) / (baseline − floor). Unknown where the floor is
  // unknown or above removable_floor_fraction of the baseline's figure.
  double floor_removed_per_pixel = kNoValue, floor_removed_flicker = kNoValue, floor_removed_global = kNoValue;
  bool meets_all() const {
    return meets_per_pixel && meets_flicker && meets_global && equal_time && floor_well_below;
  }
};

// One entry per gradient-domain row whose budget has a denoised PT row; none
// when the report ran no denoised baseline. A still (no flicker) compares
// per-pixel and global only and counts flicker as met.
std::vector<DenoiserComparison> compare_with_denoisers(const std::vector<ReportRow>& rows,
                                                       const ReferenceNoiseFloor& floor,
                                                       const DenoiserTargets& targets = {});

// The comparison as a Markdown table (what gdvr-report prints), with the
// targets in the header and the reference floor below it; "" when empty.
std::string denoiser_comparison_markdown(const std::vector<DenoiserComparison>& rows,
                                         const ReferenceNoiseFloor& floor, const DenoiserTargets& targets = {});

}  // namespace gdvr
