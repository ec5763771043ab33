// The rows of an error-vs-time report (one per method and time budget) and
// their CSV/JSON forms. Absent figures are NaN in memory, empty in the CSV and
// null in the JSON.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/util/status.h"

namespace gdvr {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

struct ReportRow {
  std::string method;          // "pt", "pt-oidn", "gpt-l1", "gpt-l2", "gpt-weighted", "tgpt-l1", ...
  std::string integrator;      // pt | gpt | tgpt
  std::string reconstruction;  // "" for pt, else the job's reconstruction.method
  double budget_s = 0;         // time_budget_s per frame given to the renderer
  int frames = 0;
  // Measured, mean over frames: stage 1 (render, feature pass, moving the
  // scene) + reconstruction + denoising, what the time budget pays for.
  double seconds_per_frame = 0;
  // The run's wall time over its frames: seconds_per_frame plus scene loading
  // and the report's own measuring (relMSE of each frame).
  double wall_seconds_per_frame = kNoValue;
  double render_seconds = 0;       // mean per frame
  double feature_seconds = 0;      // mean per frame: the feature pass (denoised methods; 0 for the others)
  double stage1_seconds = 0;       // mean per frame: render + features + moving the scene
  double reconstruct_seconds = 0;  // mean per frame
  double denoise_seconds = 0;      // mean per frame: OIDN on the frame (denoised methods)
  double spp = 0;                  // mean per frame
  double rel_mse_global = kNoValue;     // over all frames' pixels
  double rel_mse_per_pixel = kNoValue;  // mean over frames
  double flicker = kNoValue;            // animations only
  double shift_failure_rate = kNoValue;     // gpt/tgpt: mean of the shift_failure_rate layer
  double temporal_failure_rate = kNoValue;  // tgpt
  double non_finite = 0;                    // non-finite output values (counted as black)
  // PT's relMSE at the same budget over this row's (> 1: this method wins).
  double equal_time_ratio_global = kNoValue;
  double equal_time_ratio_per_pixel = kNoValue;
  // PT's global relMSE interpolated (log-log) at this row's measured seconds
  // per frame, over this row's: corrects for reconstruction time on top of the budget.
  double equal_time_ratio_interpolated = kNoValue;
  // Reconstruction vs its own unreconstructed primal (+ direct), same samples:
  // predicted from the measured variances (docs/reconstruction.md, "Predicted improvement": L2 model) and
  // achieved (global relMSE ratio).
  double predicted_improvement = kNoValue;
  double achieved_improvement = kNoValue;
  std::vector<int> frame_numbers;
  std::vector<double> frame_rel_mse_global, frame_rel_mse_per_pixel;
  std::map<std::string, int> left_out;  // FrameStats.left_out entries -> how many frames
};

// The figures the reference's own noise alone would give (core/report/reference_noise.h);
// kNoValue where unknown (a supplied reference without a variance layer).
struct ReferenceNoiseFloor {
  double global = kNoValue;
  double per_pixel = kNoValue;
  double flicker = kNoValue;
};

struct ReportMeta {
  std::string input;
  std::string frames;
  int width = 0, height = 0;
  std::string reference_source;  // "rendered (pt, N spp)" or "supplied"
  std::string reference_path;
  int reference_spp = 0;         // 0 when supplied and unknown
  double reference_seconds = 0;  // time to render it (0 when cached or supplied)
  bool reference_cached = false;
  ReferenceNoiseFloor reference_floor;
  int threads = 0;
  std::string load;  // /proc/loadavg at the start
  std::vector<std::string> notes;
};

// Fills the equal-time ratios of every row from the "pt" rows of the same
// budget (and the PT curve for the interpolated ratio).
void fill_equal_time_ratios(std::vector<ReportRow>* rows);

std::string results_csv(const std::vector<ReportRow>& rows);
std::string results_json(const ReportMeta& meta, const std::vector<ReportRow>& rows);

// Writes `text` to `path` atomically.
Status write_text_file(const std::string& path, const std::string& text);

}  // namespace gdvr
