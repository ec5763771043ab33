// gdvr-report: error against run time (docs/report.md).
//   gdvr-report JOB.json|SCENE.xml --out DIR [--reference REF.exr|ref_%04d.exr]
//       [--budgets 0.5,1,2,4] [--frames A-B] [--reference-spp N] [--methods pt,gpt-l2,...]
//       [--threads N] [--width W --height H] [--seed N] [--param NAME=VALUE ...]
// Renders PT, G-PT (L1, L2, weighted) and, for animations, T-GPT (L1, L2) at
// equal time budgets per frame against a reference (rendered with PT and
// cached in DIR/reference/, or supplied) and writes DIR/results.csv,
// results.json, plot_*.png, images/ and report.html. Progress on stderr;
// Ctrl-C cancels (the results so far stay in DIR).
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/io/color_transform.h"
#include "core/io/shipped_ocio_config.h"
#include "core/report/error_time_report.h"
#include "core/util/cli_args.h"
#include "core/util/memory_tuning.h"

namespace {

namespace fs = std::filesystem;

std::atomic<bool>& g_cancel = gdvr::tools::interrupted();

int usage(const char* msg) {
  return gdvr::tools::print_usage("gdvr-report", msg,
      "usage: gdvr-report JOB.json|SCENE.xml --out DIR [--reference REF.exr|ref_%04d.exr]\n"
      "       [--budgets 0.5,1,2,4] [--frames A-B] [--reference-spp N] [--methods pt,gpt-l2,...]\n"
      "       [--threads N] [--width W] [--height H] [--seed N] [--param NAME=VALUE ...]\n"
      "methods: pt pt-sd pt-oidn pt-sd-oidn gpt-l1 gpt-l2 gpt-weighted tgpt-l1 tgpt-l2 (default: all that apply;\n"
      "         pt-oidn and pt-sd-oidn need a build with Intel Open Image Denoise)\n");
}

using gdvr::tools::parse_int;

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  gdvr::retain_freed_memory_for_reuse();  // core/util/memory_tuning.h: batch tool
  using namespace gdvr;
  if (argc < 2) return usage(nullptr);
  std::string input;
  ErrorTimeReportOptions o;
  JobSpec overrides;
  bool have_frames = false, seed_set = false;
  std::map<std::string, std::string> params;

  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&](const char* name) -> std::string {
      if (i + 1 >= argc) {
        usage((std::string(name) + " needs a value").c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    long long v = 0;
    if (a == "--out") o.out_dir = next("--out");
    else if (a == "--reference") o.reference = next("--reference");
    else if (a == "--budgets") {
      o.budgets.clear();
      for (const std::string& b : split(next("--budgets"), ',')) {
        try {
          size_t pos;
          double s = std::stod(b, &pos);
          if (pos != b.size() || !(s > 0)) throw 0;
          o.budgets.push_back(s);
        } catch (...) {
          return usage(("--budgets: '" + b + "' is not a positive number of seconds").c_str());
        }
      }
      if (o.budgets.empty()) return usage("--budgets: expected seconds per frame, e.g. 0.5,1,2");
    } else if (a == "--frames") { overrides.frames = next("--frames"); have_frames = true; }
    else if (a == "--reference-spp") { if (!parse_int(next("--reference-spp"), 1, 1 << 20, &v)) return usage("--reference-spp: expected 1..1048576"); o.reference_spp = int(v); }
    else if (a == "--methods") o.methods = split(next("--methods"), ',');
    else if (a == "--threads") { if (!parse_int(next("--threads"), 1, 1024, &v)) return usage("--threads: expected 1..1024"); o.run.threads = int(v); }
    else if (a == "--width") { if (!parse_int(next("--width"), 1, 16384, &v)) return usage("--width: expected 1..16384"); overrides.width = int(v); }
    else if (a == "--height") { if (!parse_int(next("--height"), 1, 16384, &v)) return usage("--height: expected 1..16384"); overrides.height = int(v); }
    else if (a == "--seed") { if (!parse_int(next("--seed"), 0, (1LL << 62), &v)) return usage("--seed: expected a non-negative integer"); overrides.seed = uint64_t(v); seed_set = true; }
    else if (a == "--param" || a == "-D") {
      if (!gdvr::tools::parse_param(next("--param"), &params)) return usage("--param: expected NAME=VALUE");
    } else if (a == "-h" || a == "--help") return usage(nullptr);
    else if (!a.empty() && a[0] == '-') return usage(("unknown option " + a).c_str());
    else if (input.empty()) input = a;
    else return usage(("unexpected argument " + a).c_str());
  }
  if (input.empty()) return usage("no scene or job file given");
  if (o.out_dir.empty()) return usage("--out DIR is required");

  JobSpec& job = o.job;
  if (fs::path(input).extension() == ".json") {
    std::ifstream in(input);
    if (!in) { std::fprintf(stderr, "gdvr-report: cannot read %s\n", input.c_str()); return 1; }
    std::stringstream ss;
    ss << in.rdbuf();
    auto parsed = parse_job_json(ss.str(), input);
    if (!parsed.ok()) { std::fprintf(stderr, "gdvr-report: %s\n", parsed.status().to_string().c_str()); return 1; }
    job = std::move(parsed.value());
    o.run.base_dir = fs::absolute(input).parent_path().string();
    // A job that names its reference: relative to the job file.
    if (o.reference.empty() && !job.reference.empty())
      o.reference = fs::path(job.reference).is_relative() ? (fs::path(o.run.base_dir) / job.reference).string()
                                                          : job.reference;
  } else {
    job.scene = fs::absolute(input).string();
  }
  if (have_frames) job.frames = overrides.frames;
  if (overrides.width) job.width = overrides.width;
  if (overrides.height) job.height = overrides.height;
  if (seed_set) job.seed = overrides.seed;
  for (auto& [k, val] : params) job.params[k] = val;
  o.input_name = input;
  o.ocio_config = resolve_ocio_config_path(find_shipped_ocio_config());

  gdvr::tools::install_interrupt_handlers();
  auto log = [](const std::string& line) { std::fprintf(stderr, "gdvr-report: %s\n", line.c_str()); };
  auto report = run_error_time_report(o, log, &g_cancel);
  if (!report.ok()) {
    std::fprintf(stderr, "gdvr-report: %s\n", report.status().to_string().c_str());
    return report.status().code() == StatusCode::kCancelled ? 130 : 1;
  }
  // The key numbers on stdout: both relMSE forms and their equal-time ratios
  // against PT (> 1: better than PT) at every budget.
  std::printf("%-14s %8s %10s %8s %12s %10s %12s %10s %10s\n", "method", "budget", "s/frame", "spp", "relMSE glob",
              "ratio", "relMSE pp", "ratio", "flicker");
  auto num = [](double v, const char* f) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), f, v);
    return std::isfinite(v) ? std::string(buf) : std::string("-");
  };
  for (const ReportRow& r : report->rows)
    std::printf("%-14s %8g %10.3f %8.1f %12s %10s %12s %10s %10s\n", r.method.c_str(), r.budget_s, r.seconds_per_frame,
                r.spp, num(r.rel_mse_global, "%.4g").c_str(),
                num(r.method == "pt" ? 1.0 : r.equal_time_ratio_global, "%.3g").c_str(),
                num(r.rel_mse_per_pixel, "%.4g").c_str(),
                num(r.method == "pt" ? 1.0 : r.equal_time_ratio_per_pixel, "%.3g").c_str(), num(r.flicker, "%.3g").c_str());
  std::fprintf(stderr, "gdvr-report: wrote %s\n", report->html_path.c_str());
  return 0;
}
