// gdvr-render: renders a Mitsuba scene or a job file locally.
//   gdvr-render SCENE.xml|JOB.json --out DIR [--spp N] [--time-budget SECONDS]
//       [--frames A-B] [--threads N] [--seed N] [--integrator pt]
//       [--width W --height H] [--param NAME=VALUE ...]
// (the flags shared with gdvr-report: core/job/job_flags.h). Writes what the job's outputs block asks for, as the server and gdvr-farm
// finalize do (core/job/job_outputs.h): DIR/frame_0000.exr ..., previews, the
// video and stats.json. Ctrl-C cancels cleanly.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/denoise/oidn_denoiser.h"
#include "core/io/atomic_file.h"
#include "core/job/job_flags.h"
#include "core/job/job_outputs.h"
#include "core/job/job_runner.h"
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
      "       [--recon l1|l2|uniform|weighted|none] [--alpha A] [--window W] [--tile-size N] [--keep-negative]\n"
      "       [--data-term auto|sampled|denoised] [--exr-compression auto|zip|zips|rle|piz|none]\n"
      "       [--param NAME=VALUE ...] [--memory-limit MIB [--spill-dir DIR]]\n"
      "Flags override the job file; values are checked with the job (errors name the field).\n"
      "--memory-limit: tgpt's buffered frames beyond MIB MiB go to unnamed files in DIR (default: the\n"
      "temporary folder), read back a tile's region at a time.\n");
}

}  // namespace

int main(int argc, char** argv) {
  gdvr::retain_freed_memory_for_reuse();  // core/util/memory_tuning.h: batch tool
  using namespace gdvr;
  namespace fs = std::filesystem;
  if (argc < 2) return usage(nullptr);
  tools::JobFlags flags;
  long long memory_limit_bytes = -1;
  std::string spill_dir;
  for (int i = 1; i < argc; ++i) {
    auto taken = tools::take_job_flag(argc, argv, &i, {/* sampling = */ true, /* integrator = */ true, /* outputs = */ true}, &flags);
    if (!taken.ok()) return usage(taken.status().message().c_str());
    if (taken.value()) continue;
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") return usage(nullptr);
    if ((a == "--memory-limit" || a == "--spill-dir") && i + 1 >= argc) return usage((a + " needs a value").c_str());
    if (a == "--memory-limit") {
      long long mib = 0;
      if (!tools::parse_int(argv[++i], 0, 1LL << 30, &mib)) return usage("--memory-limit: expected MiB, >= 0");
      memory_limit_bytes = mib << 20;
      continue;
    }
    if (a == "--spill-dir") {
      spill_dir = argv[++i];
      continue;
    }
    return usage(("unknown option " + a).c_str());
  }
  if (flags.input.empty()) return usage("no scene or job file given");
  if (flags.out_dir.empty()) return usage("--out DIR is required");
  const std::string& input = flags.input;
  const std::string& out_dir = flags.out_dir;

  JobRunOptions options;
  options.threads = flags.threads;
  options.memory_limit_bytes = memory_limit_bytes;
  options.spill_dir = spill_dir;
  auto flagged_job = tools::job_from_flags(flags, &options.base_dir);
  if (!flagged_job.ok()) {
    std::fprintf(stderr, "gdvr-render: %s\n", flagged_job.status().to_string().c_str());
    return 1;
  }
  const JobSpec job = std::move(flagged_job.value());
  // T-GPT's default data term is denoised where this build has OIDN.
  if (job.integrator == Integrator::kTgpt && job.reconstruction.data_term != DataTerm::kSampled) {
    std::string why;
    options.denoiser = make_job_denoiser(flags.threads, &why);
    if (!options.denoiser && job.reconstruction.data_term == DataTerm::kDenoised) {
      std::fprintf(stderr, "gdvr-render: reconstruction.data_term 'denoised': %s\n", why.c_str());
      return 1;
    }
  }

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
    std::vector<std::pair<std::string, std::string>> header = {
        {"input", input}, {"integrator", integrator_name(job.integrator)},
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

  // Under a time budget the EXRs count too: when a frame's output waits for
  // later frames (T-GPT's window), the budget reserves what writing one costs,
  // timed on a rendered frame's buffers (about as many layers as the output).
  callbacks.estimate_frame_final_seconds = [&](const FrameBuffers& buffers) {
    return outputs.value()->estimate_write_seconds(buffers.layers);
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
