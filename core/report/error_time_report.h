// The error-vs-time report (docs/report.md): renders a job's frames with
// PT (alone, and denoised by OIDN where the build has it), G-PT (L1, L2,
// weighted) and, for animations, T-GPT (L1, L2) at a series
// of equal wall-time budgets per frame, measures each against a reference
// (rendered with high-spp PT and cached, or supplied as EXR), and writes
// results.csv, results.json, log-log plots, images and report.html into one
// folder. gdvr-report is the command-line front end.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "core/job/job_runner.h"
#include "core/job/job_spec.h"
#include "core/report/report_results.h"
#include "core/util/status.h"

namespace gdvr {

struct ErrorTimeReportOptions {
  JobSpec job;                 // scene, frames, resolution, seed, params, animation; integrator is ignored
  JobRunOptions run;           // threads, base_dir, asset_root
  std::string input_name;      // how the report names its input
  std::string out_dir;
  // Supplied reference: one EXR (single frame) or a pattern with a printf
  // integer ("ref_%04d.exr") for sequences. Empty: render one with PT.
  std::string reference;
  int reference_spp = 1024;
  std::vector<double> budgets = {0.5, 1, 2, 4};  // seconds per frame
  // Methods to run, from pt, pt-sd, pt-oidn, pt-sd-oidn, gpt-l1, gpt-l2,
  // gpt-weighted, tgpt-l1, tgpt-l2, tgpt-l1-sampled, tgpt-l1-oidn; empty: all
  // that apply but the last two (tgpt only for animations of 2+ frames, the
  // -oidn ones only in a build with OIDN, which fails with a message saying
  // so when one of them is asked for). The tgpt methods have the job
  // default's data term (denoised in a build with OIDN); tgpt-l1-sampled the
  // sampled one; tgpt-l1-oidn is tgpt-l1 denoised again afterwards.
  std::vector<std::string> methods;
  std::string ocio_config;  // display transform of the images; empty: a plain sRGB encoding
};

struct ErrorTimeReport {
  ReportMeta meta;
  std::vector<ReportRow> rows;
  std::string html_path;
};

// `log` receives progress lines (no newline); may be empty.
Expected<ErrorTimeReport> run_error_time_report(const ErrorTimeReportOptions& options,
                                                const std::function<void(const std::string&)>& log,
                                                const std::atomic<bool>* cancel);

// The methods known to the report, in display order.
const std::vector<std::string>& report_method_names();

// A stable 64-bit FNV-1a hash, hex (the reference cache key).
std::string fnv1a_hex(const std::string& data);

}  // namespace gdvr
