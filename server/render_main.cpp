// gdvr-render: renders a Mitsuba scene or a job file locally.
//   gdvr-render SCENE.xml|JOB.json --out DIR [--spp N] [--time-budget SECONDS]
//       [--frames A-B] [--threads N] [--seed N] [--integrator pt]
//       [--width W --height H] [--param NAME=VALUE ...]
// Writes what the job's outputs block asks for, as the server and gdvr-farm
// finalize do (core/job/job_outputs.h): DIR/frame_0000.exr ..., previews, the
// video and stats.json. Ctrl-C cancels cleanly.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "core/gradient/gpt_settings.h"
#include "core/io/atomic_file.h"
#include "core/job/job_outputs.h"
#include "core/job/job_runner.h"
#include "core/recon/recon_settings.h"
#include "core/temporal/tgpt_settings.h"
#include "core/job/job_spec.h"
#include "core/util/cli_args.h"
#include "core/util/memory_tuning.h"

namespace {

std::atomic<bool>& g_cancel = gdvr::tools::interrupted();

int usage(const char* msg) {
  return gdvr::tools::print_usage("gdvr-render", msg,
      "usage: gdvr-render SCENE.xml|JOB.json --out DIR [--spp N] [--time-budget SECONDS]\n"
      "       [--frames A-B] [--threads N] [--seed N] [--integrator pt|gpt|tgpt] [--width W] [--height H]\n"
      "       [--shift replay|reconnect|hybrid] [--temporal-shift replay|reconnect]\n"
      "       [--recon l1|l2|uniform|weighted|none] [--alpha A] [--window W] [--keep-negative]\n"
      "       [--param NAME=VALUE ...]\n"
      "Flags override the job file; values are checked with the job (errors name the field).\n");
}

using gdvr::tools::parse_int;

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

  gdvr::tools::install_interrupt_handlers();

  // The job's output stage (core/job/job_outputs.h): the same files the
  // server and gdvr-farm finalize write for this job.
  auto frame_list = parse_frame_range(job.frames);
  if (!frame_list.ok()) { std::fprintf(stderr, "gdvr-render: job.frames: %s\n", frame_list.status().message().c_str()); return 1; }
  JobOutputs::Options output_options;
  output_options.asset_root = options.base_dir.empty() ? fs::current_path().string() : options.base_dir;
  if (!frame_list->empty()) {
    Status valid = JobOutputs::validate(job, output_options, frame_list->front());
    if (!valid.ok()) { std::fprintf(stderr, "gdvr-render: %s\n", valid.to_string().c_str()); return 1; }
  }
  auto outputs = JobOutputs::open(job, *frame_list, out_dir, output_options);
  if (!outputs.ok()) { std::fprintf(stderr, "gdvr-render: %s\n", outputs.status().to_string().c_str()); return 1; }

  std::vector<WrittenFrame> written;
  Status write_status;
  auto write_stats = [&](const Status& st) {
    std::vector<std::pair<std::string, std::string>> header = {{"input", input}, {"integrator", job.integrator},
                                                               {"state", st.ok() ? "completed" : status_code_name(st.code())}};
    if (!st.ok()) header.push_back({"reason", st.message()});
    return write_text_atomic((fs::path(out_dir) / "stats.json").string(), stats_json(header, int(frame_list->size()), written));
  };

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
    if (!write_status.ok()) return;
    auto w = outputs.value()->write_frame(out);
    if (!w.ok()) { write_status = w.status(); return; }
    if (Status st = outputs.value()->add_to_video(out.frame); !st.ok()) { write_status = st; return; }
    written.push_back(*w);
    const FrameStats& s = w->stats;
    std::fprintf(stderr, "\rframe %d: %.2f s, %d spp, %.2f Mrays/s -> %s\n", s.frame, s.render_seconds, s.spp,
                 s.rays_per_second * 1e-6, (fs::path(out_dir) / w->file).string().c_str());
  };

  Status st = run_job(job, options, callbacks, &g_cancel);
  if (st.ok() && write_status.ok()) {
    auto video = outputs.value()->finish();
    if (!video.ok()) write_status = video.status();
  }
  outputs.value().reset();  // an unfinished encoder deletes its partial file
  if (Status s = write_stats(st.ok() ? write_status : st); !s.ok() && write_status.ok()) write_status = s;
  if (!st.ok()) {
    std::fprintf(stderr, "\ngdvr-render: %s\n", st.to_string().c_str());
    return st.code() == StatusCode::kCancelled ? 130 : 1;
  }
  if (!write_status.ok()) {
    std::fprintf(stderr, "gdvr-render: %s\n", write_status.to_string().c_str());
    return 1;
  }
  std::fprintf(stderr, "gdvr-render: wrote %zu frame(s) to %s\n", written.size(), out_dir.c_str());
  return 0;
}
