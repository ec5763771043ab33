// gdvr-render: renders a Mitsuba scene or a job file locally.
//   gdvr-render SCENE.xml|JOB.json --out DIR [--spp N] [--time-budget SECONDS]
//       [--frames A-B] [--threads N] [--seed N] [--integrator pt]
//       [--width W --height H] [--param NAME=VALUE ...]
// Writes DIR/frame_0000.exr ... and DIR/stats.json. Ctrl-C cancels cleanly.
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/io/image_io.h"
#include "core/gradient/gpt_settings.h"
#include "core/job/job_runner.h"
#include "core/recon/recon_settings.h"
#include "core/temporal/tgpt_settings.h"
#include "core/job/job_spec.h"
#include "core/tools/cli_args.h"
#include "core/util/memory_tuning.h"

namespace {

std::atomic<bool> g_cancel{false};
void on_signal(int) { g_cancel = true; }

int usage(const char* msg) {
  if (msg) std::fprintf(stderr, "gdvr-render: %s\n", msg);
  std::fprintf(stderr,
               "usage: gdvr-render SCENE.xml|JOB.json --out DIR [--spp N] [--time-budget SECONDS]\n"
               "       [--frames A-B] [--threads N] [--seed N] [--integrator pt|gpt|tgpt] [--width W] [--height H]\n"
               "       [--shift replay|reconnect|hybrid] [--temporal-shift replay|reconnect]\n"
               "       [--recon l1|l2|uniform|weighted|none] [--alpha A] [--window W] [--keep-negative]\n"
               "       [--param NAME=VALUE ...]\n"
               "Flags override the job file; values are checked with the job (errors name the field).\n");
  return 2;
}

using gdvr::tools::parse_int;

std::string frame_name(int frame) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "frame_%04d.exr", frame);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  gdvr::retain_freed_memory_for_reuse();  // core/util/memory_tuning.h: batch tool
  using namespace gdvr;
  namespace fs = std::filesystem;
  if (argc < 2) return usage(nullptr);
  std::string input, out_dir;
  JobSpec job;
  bool have_frames = false;
  JobSpec overrides;
  int threads = 0;
  bool seed_set = false, integrator_set = false, alpha_set = false, keep_negative = false;
  std::string shift, temporal_shift, recon;
  int window = 0;
  std::map<std::string, std::string> params;

  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&](const char* name) -> const char* {
      if (i + 1 >= argc) {
        usage((std::string(name) + " needs a value").c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    long long v = 0;
    if (a == "--out") out_dir = next("--out");
    else if (a == "--spp") { if (!parse_int(next("--spp"), 1, 1 << 24, &v)) return usage("--spp: expected 1..16777216"); overrides.spp = int(v); }
    else if (a == "--time-budget") {
      if (!gdvr::tools::parse_number(next("--time-budget"), 0, 1e9, &overrides.time_budget_s) || !(overrides.time_budget_s > 0))
        return usage("--time-budget: expected a positive number of seconds");
    }
    else if (a == "--frames") { overrides.frames = next("--frames"); have_frames = true; }
    else if (a == "--threads") { if (!parse_int(next("--threads"), 1, 1024, &v)) return usage("--threads: expected 1..1024"); threads = int(v); }
    else if (a == "--seed") { if (!parse_int(next("--seed"), 0, (1LL << 62), &v)) return usage("--seed: expected a non-negative integer"); overrides.seed = uint64_t(v); seed_set = true; }
    else if (a == "--integrator") { overrides.integrator = next("--integrator"); integrator_set = true; }
    else if (a == "--shift") shift = next("--shift");
    else if (a == "--temporal-shift") temporal_shift = next("--temporal-shift");
    else if (a == "--recon") recon = next("--recon");
    else if (a == "--keep-negative") keep_negative = true;
    else if (a == "--alpha") {
      const char* text = next("--alpha");
      char* end = nullptr;
      overrides.reconstruction.alpha = std::strtod(text, &end);
      if (end == text || *end != '\0' || !(overrides.reconstruction.alpha >= 0) || !std::isfinite(overrides.reconstruction.alpha))
        return usage("--alpha: expected a finite number >= 0");
      alpha_set = true;
    }
    else if (a == "--window") { if (!parse_int(next("--window"), 1, 1000, &v)) return usage("--window: expected 1..1000"); window = int(v); }
    else if (a == "--width") { if (!parse_int(next("--width"), 1, 16384, &v)) return usage("--width: expected 1..16384"); overrides.width = int(v); }
    else if (a == "--height") { if (!parse_int(next("--height"), 1, 16384, &v)) return usage("--height: expected 1..16384"); overrides.height = int(v); }
    else if (a == "--param" || a == "-D") {
      if (!gdvr::tools::parse_param(next("--param"), &params)) return usage("--param: expected NAME=VALUE");
    } else if (a == "-h" || a == "--help") return usage(nullptr);
    else if (!a.empty() && a[0] == '-') return usage(("unknown option " + a).c_str());
    else if (input.empty()) input = a;
    else return usage(("unexpected argument " + a).c_str());
  }
  if (input.empty()) return usage("no scene or job file given");
  // The same names the job file accepts (checked here too: a pt job ignores them).
  if (!shift.empty() && !parse_shift_mapping(shift).ok()) return usage(parse_shift_mapping(shift).status().message().c_str());
  if (!temporal_shift.empty() && !parse_temporal_shift(temporal_shift).ok())
    return usage(parse_temporal_shift(temporal_shift).status().message().c_str());
  if (!recon.empty() && !parse_recon_method(recon).ok()) return usage(parse_recon_method(recon).status().message().c_str());
  if (out_dir.empty()) return usage("--out DIR is required");

  JobRunOptions options;
  options.threads = threads;
  if (fs::path(input).extension() == ".json") {
    std::ifstream in(input);
    if (!in) { std::fprintf(stderr, "gdvr-render: cannot read %s\n", input.c_str()); return 1; }
    std::stringstream ss;
    ss << in.rdbuf();
    auto parsed = parse_job_json(ss.str(), input);
    if (!parsed.ok()) { std::fprintf(stderr, "gdvr-render: %s\n", parsed.status().to_string().c_str()); return 1; }
    job = std::move(parsed.value());
    options.base_dir = fs::absolute(input).parent_path().string();
  } else {
    job.scene = fs::absolute(input).string();
  }
  if (overrides.spp) job.spp = overrides.spp;
  if (overrides.time_budget_s > 0) job.time_budget_s = overrides.time_budget_s;
  if (have_frames) job.frames = overrides.frames;
  if (overrides.width) job.width = overrides.width;
  if (overrides.height) job.height = overrides.height;
  if (seed_set) job.seed = overrides.seed;
  if (integrator_set) job.integrator = overrides.integrator;
  if (!shift.empty()) job.shift = shift;
  if (!temporal_shift.empty()) job.temporal_shift = temporal_shift;
  if (!recon.empty()) job.reconstruction.method = recon;
  if (alpha_set) job.reconstruction.alpha = overrides.reconstruction.alpha;
  if (window > 0) job.reconstruction.window = window;
  if (keep_negative) job.reconstruction.clamp_negative = false;
  for (auto& [k, val] : params) job.params[k] = val;

  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) { std::fprintf(stderr, "gdvr-render: cannot create %s: %s\n", out_dir.c_str(), ec.message().c_str()); return 1; }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  nlohmann::json stats = nlohmann::json::object();
  stats["input"] = input;
  stats["integrator"] = job.integrator;
  stats["frames"] = nlohmann::json::array();
  Status write_status;
  double total_seconds = 0;
  uint64_t total_rays = 0, total_temporal_rays = 0, total_samples = 0;
  std::map<std::string, int> left_out_totals;

  JobCallbacks callbacks;
  // Progress at most 4 times a second: a tile-level callback would flood logs.
  auto last_print = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  callbacks.on_progress = [&](const JobProgress& p) {
    auto now = std::chrono::steady_clock::now();
    if (now - last_print < std::chrono::milliseconds(250)) return;
    last_print = now;
    std::fprintf(stderr, "\r[%3.0f%%] frames %d/%d  ETA %s   ", p.fraction * 100.0, p.frames_done, p.frames_total,
                 p.eta_seconds < 0 ? "--" : (std::to_string(int(p.eta_seconds + 0.5)) + "s").c_str());
    std::fflush(stderr);
  };
  callbacks.on_frame_final = [&](const FrameOutput& out) {
    fs::path path = fs::path(out_dir) / frame_name(out.frame);
    Status st = write_exr(path.string(), out.image);
    if (!st.ok() && write_status.ok()) write_status = st;
    const FrameStats& s = out.stats;
    stats["frames"].push_back({{"frame", s.frame}, {"file", path.filename().string()}, {"render_seconds", s.render_seconds},
                               {"spp", s.spp}, {"samples", s.samples}, {"rays", s.rays}, {"temporal_rays", s.temporal_rays},
                               {"samples_per_second", s.samples_per_second}, {"rays_per_second", s.rays_per_second},
                               {"left_out", s.left_out}});
    total_seconds += s.render_seconds;
    total_rays += s.rays;
    total_temporal_rays += s.temporal_rays;
    total_samples += s.samples;
    for (const auto& l : s.left_out) left_out_totals[l]++;
    std::fprintf(stderr, "\rframe %d: %.2f s, %d spp, %.2f Mrays/s -> %s\n", s.frame, s.render_seconds, s.spp,
                 s.rays_per_second * 1e-6, path.string().c_str());
  };

  Status st = run_job(job, options, callbacks, &g_cancel);
  stats["total"] = {{"render_seconds", total_seconds}, {"rays", total_rays}, {"temporal_rays", total_temporal_rays},
                    {"samples", total_samples},
                    {"rays_per_second", total_seconds > 0 ? double(total_rays) / total_seconds : 0.0},
                    {"left_out", left_out_totals}};
  stats["status"] = st.ok() ? "completed" : status_code_name(st.code());
  if (!st.ok()) stats["error"] = st.message();
  std::ofstream(fs::path(out_dir) / "stats.json") << stats.dump(2) << "\n";
  if (!st.ok()) {
    std::fprintf(stderr, "\ngdvr-render: %s\n", st.to_string().c_str());
    return st.code() == StatusCode::kCancelled ? 130 : 1;
  }
  if (!write_status.ok()) {
    std::fprintf(stderr, "gdvr-render: %s\n", write_status.to_string().c_str());
    return 1;
  }
  std::fprintf(stderr, "gdvr-render: wrote %zu frame(s) to %s\n", stats["frames"].size(), out_dir.c_str());
  return 0;
}
