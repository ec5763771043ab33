// gdvr-report: error against run time (docs/report.md).
//   gdvr-report JOB.json|SCENE.xml --out DIR [--reference REF.exr|ref_%04d.exr]
//       [--budgets 0.5,1,2,4] [--frames A-B] [--reference-spp N] [--methods pt,gpt-l2,...]
//       [--threads N] [--width W --height H] [--seed N] [--param NAME=VALUE ...]
// (the flags shared with gdvr-render: core/job/job_flags.h)
// Renders PT, G-PT (L1, L2, weighted) and, for animations, T-GPT (L1, L2) at
// equal time budgets per frame against a reference (rendered with PT and
// cached in DIR/reference/, or supplied) and writes DIR/results.csv,
// results.json, plot_*.png, images/ and report.html. Progress on stderr;
// Ctrl-C cancels (the results so far stay in DIR).
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "core/io/color_transform.h"
#include "core/io/shipped_ocio_config.h"
#include "core/job/job_flags.h"
#include "core/report/denoiser_comparison.h"
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
      "methods: pt pt-sd pt-oidn pt-sd-oidn gpt-l1 gpt-l2 gpt-weighted tgpt-l1 tgpt-l2 tgpt-l1-sampled\n"
      "         tgpt-l1-oidn (default: all that apply but tgpt-l1-sampled and tgpt-l1-oidn; the -oidn\n"
      "         methods need a build with Intel Open Image Denoise; the tgpt methods use it for their\n"
      "         data term where the build has it)\n");
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
  ErrorTimeReportOptions o;
  tools::JobFlags flags;
  for (int i = 1; i < argc; ++i) {
    auto taken = tools::take_job_flag(argc, argv, &i, tools::JobFlagSet{}, &flags);
    if (!taken.ok()) return usage(taken.status().message().c_str());
    if (taken.value()) continue;
    std::string a = argv[i];
    auto next = [&](const char* name) -> std::string {
      if (i + 1 >= argc) {
        usage((std::string(name) + " needs a value").c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    long long v = 0;
    if (a == "--reference") o.reference = next("--reference");
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
    } else if (a == "--reference-spp") {
      if (!parse_int(next("--reference-spp"), 1, kMaxJobSpp, &v))
        return usage(("--reference-spp: expected 1.." + std::to_string(kMaxJobSpp)).c_str());
      o.reference_spp = int(v);
    } else if (a == "--methods") o.methods = split(next("--methods"), ',');
    else if (a == "-h" || a == "--help") return usage(nullptr);
    else return usage(("unknown option " + a).c_str());
  }
  if (flags.input.empty()) return usage("no scene or job file given");
  if (flags.out_dir.empty()) return usage("--out DIR is required");
  const std::string& input = flags.input;
  o.out_dir = flags.out_dir;
  o.run.threads = flags.threads;

  auto job = tools::job_from_flags(flags, &o.run.base_dir);
  if (!job.ok()) {
    std::fprintf(stderr, "gdvr-report: %s\n", job.status().to_string().c_str());
    return 1;
  }
  o.job = std::move(job.value());
  // A job that names its reference: relative to the job file.
  if (o.reference.empty() && !o.job.reference.empty() && !o.run.base_dir.empty())
    o.reference = fs::path(o.job.reference).is_relative() ? (fs::path(o.run.base_dir) / o.job.reference).string()
                                                          : o.job.reference;
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
  // The comparison users make before switching: against the best denoised PT.
  const std::string vs_denoiser =
      denoiser_comparison_markdown(compare_with_denoisers(report->rows, report->meta.reference_floor),
                                   report->meta.reference_floor);
  if (!vs_denoiser.empty()) std::printf("\n%s", vs_denoiser.c_str());
  std::fprintf(stderr, "gdvr-report: wrote %s\n", report->html_path.c_str());
  return 0;
}
