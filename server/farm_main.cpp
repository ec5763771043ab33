// gdvr-farm: the two stages of a job as commands a render-farm manager
// (OpenCue, Deadline, Flamenco, a Kubernetes Indexed Job, a shell loop) can
// schedule on any number of machines sharing one folder. gdvr does not become
// a scheduler: it only makes each command idempotent and restartable.
//
//   gdvr-farm render   JOB.json (--frames A-B | --chunk-size N --chunk-index I) --buffers DIR [--threads N]
//   gdvr-farm finalize JOB.json [--frames A-B] --buffers DIR --out OUT [--video] [--ocio-config PATH]
//   gdvr-farm finalize JOB.json [--frames A-B] --tiles T0-T1 --buffers DIR --out OUT
//   gdvr-farm tiles    JOB.json [--tiles-per-task N]   one tile range per line (tgpt's tiled finalize)
//   gdvr-farm chunks   JOB.json --chunk-size N      one chunk per line, render-farm syntax
//   gdvr-farm status   JOB.json [--frames A-B] --buffers DIR [--out OUT]   exit 0 once all buffers are complete
//                      (with --out: and every frame final or with all its tile parts)
//
// The files they share are core/farm/'s. render writes DIR/buffers_0001.exr (every pre-reconstruction layer, float)
// and then DIR/buffers_0001.json (FrameStats and a fingerprint of the job);
// the JSON is the commit marker, so a frame counts as done only once both
// files are in place and agree. finalize reads the buffers each frame's
// reconstruction window needs and writes OUT/frame_0001.exr, the OCIO preview
// OUT/preview_0001.png and, with --video, OUT/video.mp4 (frames encoded in
// order) - the same names gdvr-server uses.
//
// Exit codes: 0 done, 1 failed, 2 usage, 3 buffers missing (render first),
// 130 cancelled (SIGINT/SIGTERM, as on farm pre-emption).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/denoise/oidn_denoiser.h"
#include "core/farm/buffer_store.h"
#include "core/farm/farm_job.h"
#include "core/farm/tile_parts.h"
#include "core/io/atomic_file.h"
#include "core/job/job_outputs.h"
#include "core/job/job_runner.h"
#include "core/job/job_spec.h"
#include "core/util/cli_args.h"
#include "core/util/memory_tuning.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;
using namespace farm;  // the protocol the two stages share (core/farm/)

constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;
constexpr int kExitMissingBuffers = 3;
constexpr int kExitCancelled = 130;

std::atomic<bool>& g_cancel = gdvr::tools::interrupted();

int usage(const char* msg) {
  return gdvr::tools::print_usage("gdvr-farm", msg,
      "usage: gdvr-farm render JOB.json (--frames A-B | --chunk-size N --chunk-index I) --buffers DIR\n"
      "                                     [--threads N]\n"
      "       gdvr-farm finalize JOB.json [--frames A-B | --chunk-size N --chunk-index I] --buffers DIR\n"
      "                                     --out OUT [--video] [--ocio-config PATH]\n"
      "       gdvr-farm finalize JOB.json [--frames A-B] --tiles T0-T1 --buffers DIR --out OUT\n"
      "       gdvr-farm tiles JOB.json [--tiles-per-task N]\n"
      "       gdvr-farm chunks JOB.json --chunk-size N\n"
      "       gdvr-farm status JOB.json [--frames A-B] --buffers DIR [--out OUT]\n"
      "Frames use render-farm syntax (\"1-100\", \"1-100x2\", \"1,5,10-20\") and default to the job's.\n"
      "exit codes: 0 done, 1 failed, 2 usage, 3 buffers missing, 130 cancelled\n");
}

// A failure that already carries its exit code, so helpers can return one
// value up to main().
struct Failure {
  int exit_code = 0;  // 0: no failure
  std::string message;
  bool failed() const { return exit_code != 0; }
};
Failure fail(int code, std::string message) { return {code, std::move(message)}; }
Failure fail(const Status& st) {
  return {st.code() == StatusCode::kCancelled ? kExitCancelled : kExitFailed, st.to_string()};
}

using gdvr::tools::parse_int;

// ---- render ----

Failure cmd_render(const FarmJob& job, const std::vector<int>& frames, const std::string& dir, int threads) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return fail(kExitFailed, "--buffers: cannot create '" + dir + "': " + ec.message());
  remove_temporaries_of_dead_writers(dir);

  std::vector<int> todo;
  for (int f : frames) {
    BufferCheck c = check_buffers(job, dir, f);
    if (c.state == BufferState::kForeign) return fail(kExitFailed, "frame " + std::to_string(f) + ": " + c.why);
    if (c.state == BufferState::kComplete) {
      std::fprintf(stderr, "frame %d: buffers already complete, skipped\n", f);
      continue;
    }
    todo.push_back(f);
  }
  std::fprintf(stderr, "gdvr-farm render: %zu of %zu frame(s) [%s] to render into %s\n", todo.size(), frames.size(),
               format_frames(frames).c_str(), dir.c_str());
  if (todo.empty()) return {};

  JobRunOptions options = job.options;
  options.threads = threads;
  // T-GPT's data term is made here, in stage 1: the same denoiser as
  // gdvr-render's, so that the farm's frames equal a single process's. A
  // worker without one renders the sampled data term (said in each frame's
  // notes), or refuses a job that asks for "denoised".
  if (job.spec.integrator == Integrator::kTgpt && job.spec.reconstruction.data_term != DataTerm::kSampled) {
    std::string why;
    options.denoiser = make_job_denoiser(threads, &why);
    if (!options.denoiser && job.spec.reconstruction.data_term == DataTerm::kDenoised)
      return fail(kExitFailed, "reconstruction.data_term 'denoised': " + why);
  }
  auto on_buffers = [&](FrameBuffers&& fb) -> Status {
    GDVR_RETURN_IF_ERROR(write_buffers(job, dir, fb).with_context("frame " + std::to_string(fb.frame) + ": "));
    std::fprintf(stderr, "frame %d: %.2f s, %d spp, %.2f Mrays/s -> %s\n", fb.frame, fb.stats.render_seconds,
                 fb.stats.spp, fb.stats.rays_per_second * 1e-6,
                 (fs::path(dir) / buffers_exr_name(fb.frame)).string().c_str());
    return Status::Ok();
  };
  Status st = render_job_buffers(job.spec, options, todo, on_buffers, nullptr, &g_cancel);
  if (!st.ok()) return fail(st);
  return {};
}

// ---- finalize ----

// The job frame after `frame` (its dt layer's partner), or none.
std::vector<int> frame_and_successor(const FarmJob& job, int frame) {
  auto it = std::upper_bound(job.frames.begin(), job.frames.end(), frame);
  if (it == job.frames.end()) return {frame};
  return {frame, *it};
}

// The tile grid of the job's reconstruction for the size of `buffers`' frames.
Expected<TileGrid> grid_of(const JobFinalizer& finalizer, const FrameBuffers& buffers) {
  if (buffers.on_disk) return finalizer.tile_grid(buffers.on_disk->width(), buffers.on_disk->height());
  const ImageLayer* direct = buffers.layers.find("direct");
  if (!direct) return invalid_argument("frame " + std::to_string(buffers.frame) + ": buffers lack the 'direct' layer");
  return finalizer.tile_grid(direct->image.width(), direct->image.height());
}

// Reads into `loaded` the buffers of `frames` it lacks (for finalizing
// `for_frame`): whole, or `by_region`, left in their files to be read a
// region at a time.
Failure load_buffers(const FarmJob& job, const std::string& buffers_dir, const std::vector<int>& frames, int for_frame,
                     std::map<int, FrameBuffers>* loaded, bool by_region = false) {
  for (int n : frames) {
    if (loaded->count(n)) continue;
    auto fb = by_region ? open_buffers(job, buffers_dir, n, for_frame) : read_buffers(job, buffers_dir, n, for_frame);
    if (!fb.ok())
      return fail(fb.status().code() == StatusCode::kNotFound ? kExitMissingBuffers : kExitFailed,
                  fb.status().to_string());
    (*loaded)[n] = std::move(fb.value());
  }
  return {};
}

// Before the first output: every buffer the task reads must be complete, so a
// task scheduled too early fails at once and names everything still missing.
Failure check_inputs(const FarmJob& job, const std::string& buffers_dir, const std::set<int>& needed) {
  std::vector<std::string> missing;
  for (int n : needed) {
    BufferCheck c = check_buffers(job, buffers_dir, n);
    if (c.state == BufferState::kForeign) return fail(kExitFailed, "frame " + std::to_string(n) + ": " + c.why);
    if (c.state == BufferState::kMissing)
      missing.push_back("frame " + std::to_string(n) + ": " + (fs::path(buffers_dir) / buffers_exr_name(n)).string() +
                        " (" + c.why + ")");
  }
  if (missing.empty()) return {};
  std::string msg = "buffers missing for " + std::to_string(missing.size()) + " frame(s); render them first:";
  for (const auto& m : missing) msg += "\n  " + m;
  return fail(kExitMissingBuffers, msg);
}

// ---- finalize --tiles: this task's tiles of each frame, as tile parts ----

Failure cmd_finalize_tiles(const FarmJob& job, const std::vector<int>& frames, const std::vector<int>& tiles,
                           const std::string& buffers_dir, const std::string& out_dir) {
  auto finalizer = JobFinalizer::create(job.spec);
  if (!finalizer.ok()) return fail(finalizer.status());
  // pt and gpt have no window solve to split: their one "tile" is the whole
  // finalize, which the finalize without --tiles does. Farm templates can
  // then run a tile step for every job.
  if (auto probe = finalizer.value()->tile_grid(1, 1); probe.status().code() == StatusCode::kUnimplemented) {
    std::fprintf(stderr, "gdvr-farm finalize: %s: nothing to do for --tiles; the finalize without --tiles "
                 "finalizes its frames\n", integrator_name(job.spec.integrator));
    return {};
  }
  std::error_code ec;
  fs::create_directories(fs::path(out_dir) / "tiles", ec);
  if (ec) return fail(kExitFailed, "--out: cannot create '" + out_dir + "/tiles': " + ec.message());
  remove_temporaries_of_dead_writers((fs::path(out_dir) / "tiles").string());
  // A frame already final, or whose parts of these tiles are all written, is done.
  auto done = [&](int f) {
    if (fs::exists(fs::path(out_dir) / frame_file_name(f), ec)) return true;
    for (int t : tiles)
      if (!fs::exists(tile_part_path(out_dir, f, t), ec)) return false;
    return true;
  };
  std::set<int> needed;
  std::map<int, int> last_use;
  for (int f : frames)
    if (!done(f))
      for (int n : finalizer.value()->frames_needed(f)) {
        needed.insert(n);
        last_use[n] = f;
      }
  if (Failure bad = check_inputs(job, buffers_dir, needed); bad.failed()) return bad;
  std::map<int, FrameBuffers> loaded;
  int written = 0;
  for (int f : frames) {
    if (g_cancel) return fail(cancelled("cancelled"));
    if (done(f)) continue;
    // Only the tiles' padded regions of the window's frames are read, each
    // when its tile is solved: the task never holds a frame whole.
    if (Failure bad = load_buffers(job, buffers_dir, finalizer.value()->frames_needed(f), f, &loaded,
                                   /* by_region = */ true);
        bad.failed())
      return bad;
    auto grid = grid_of(*finalizer.value(), loaded.at(f));
    if (!grid.ok()) return fail(grid.status());
    auto solved = finalizer.value()->reconstruct_tiles(f, tiles, loaded);
    if (!solved.ok()) return fail(solved.status());
    for (int t : tiles)
      if (Status st = write_tile_part(out_dir, f, grid.value(), t, solved.value()); !st.ok()) return fail(st);
    ++written;
    std::fprintf(stderr, "frame %d: tiles %s of %s -> %s\n", f, format_frames(tiles).c_str(),
                 grid->to_string().c_str(), (fs::path(out_dir) / "tiles").string().c_str());
    for (auto it = loaded.begin(); it != loaded.end();)
      it = last_use[it->first] <= f ? loaded.erase(it) : std::next(it);
  }
  std::fprintf(stderr, "gdvr-farm finalize: tiles %s of %d frame(s) written; run finalize without --tiles to "
               "assemble the frames\n", format_frames(tiles).c_str(), written);
  return {};
}

Failure cmd_finalize(const FarmJob& job, const std::vector<int>& frames, const std::string& buffers_dir,
                     const std::string& out_dir, bool video, const std::string& ocio_flag) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) return fail(kExitFailed, "--out: cannot create '" + out_dir + "': " + ec.message());
  remove_temporaries_of_dead_writers(out_dir);

  // One finalizer for the task: a T-GPT window is solved once for all of the
  // task's frames it holds, not once per frame.
  auto finalizer = JobFinalizer::create(job.spec);
  if (!finalizer.ok()) return fail(finalizer.status());

  // A frame whose tiles were finalized by --tiles tasks is assembled from
  // their parts: it reads only its own buffers and the next frame's.
  auto frames_read = [&](int f) {
    return has_tile_parts(out_dir, f) ? frame_and_successor(job, f) : finalizer.value()->frames_needed(f);
  };
  std::set<int> needed;
  for (int f : frames)
    if (!fs::exists(fs::path(out_dir) / frame_file_name(f), ec))
      for (int n : frames_read(f)) needed.insert(n);
  if (Failure bad = check_inputs(job, buffers_dir, needed); bad.failed()) return bad;

  // The job's output stage (core/job/job_outputs.h), as gdvr-render and the
  // server use it; the video only where this task is asked for it (a task
  // holding the whole range, usually the last step of a farm job).
  JobSpec output_spec = job.spec;
  if (video && output_spec.outputs.video_codec == "none")
    std::fprintf(stderr, "gdvr-farm finalize: job.outputs.video_codec is 'none': no video\n");
  if (!video) output_spec.outputs.video_codec = "none";
  const JobOutputs::Options output_options{ocio_flag, fs::path(job.path).parent_path().string()};
  if (Status st = JobOutputs::validate(output_spec, output_options, frames.front()); !st.ok())
    return fail(st.with_context(job.path + ": "));
  auto outputs = JobOutputs::open(output_spec, frames, out_dir, output_options);
  if (!outputs.ok()) return fail(outputs.status().with_context(job.path + ": "));

  // Buffers stay loaded while a later frame of this run still needs them
  // (the temporal window slides over neighbouring frames).
  std::map<int, FrameBuffers> loaded;
  std::map<int, int> last_use;
  for (int f : frames)
    for (int n : frames_read(f)) last_use[n] = f;
  int finalized = 0, skipped = 0;
  for (int f : frames) {
    if (g_cancel) return fail(cancelled("cancelled"));
    if (fs::exists(fs::path(out_dir) / frame_file_name(f), ec)) {
      // Finalized by an earlier (perhaps killed) run: its preview and video
      // frame come from the EXR as written, so they are the same either way.
      ++skipped;
      if (Status st = outputs.value()->complete_earlier_frame(f); !st.ok()) return fail(st);
    } else {
      const bool assemble = has_tile_parts(out_dir, f);
      if (Failure bad = load_buffers(job, buffers_dir, frames_read(f), f, &loaded); bad.failed()) return bad;
      Expected<FrameOutput> out = invalid_argument("unset");
      std::optional<TileGrid> grid;
      if (assemble) {
        auto g = grid_of(*finalizer.value(), loaded.at(f));
        if (!g.ok()) return fail(g.status());
        grid = g.value();
        auto solved = assemble_tile_parts(out_dir, f, *grid);
        if (!solved.ok())
          return fail(solved.status().code() == StatusCode::kNotFound ? kExitMissingBuffers : kExitFailed,
                      solved.status().to_string());
        out = finalizer.value()->finalize_solved(f, loaded, std::move(solved.value()));
      } else {
        out = finalizer.value()->finalize(f, loaded);
      }
      if (!out.ok()) return fail(out.status());
      auto written = outputs.value()->write_frame(out.value());
      if (!written.ok()) return fail(written.status());
      if (Status st = write_text_atomic((fs::path(buffers_dir) / final_stats_name(f)).string(),
                                        frame_entry_json(written.value()) + "\n");
          !st.ok())
        return fail(st);
      ++finalized;
      if (grid) remove_tile_parts(out_dir, f, *grid);
      std::fprintf(stderr, "frame %d: %s -> %s\n", f,
                   assemble ? "assembled from its tiles" : ("reconstruct " + std::to_string(out->stats.reconstruct_seconds) + " s").c_str(),
                   (fs::path(out_dir) / written->file).string().c_str());
      for (auto it = loaded.begin(); it != loaded.end();)
        it = last_use[it->first] <= f ? loaded.erase(it) : std::next(it);
    }
    if (Status st = outputs.value()->add_to_video(f); !st.ok()) return fail(st.with_context("frame " + std::to_string(f) + ": "));
  }
  auto video_name = outputs.value()->finish();
  if (!video_name.ok()) return fail(video_name.status());
  if (Status st = write_job_stats(job, buffers_dir, out_dir); !st.ok()) return fail(st);
  if (!video_name->empty())
    std::fprintf(stderr, "gdvr-farm finalize: %lld frame(s) -> %s\n", (long long)outputs.value()->video_frames(),
                 (fs::path(out_dir) / video_name.value()).string().c_str());
  std::fprintf(stderr, "gdvr-farm finalize: %d frame(s) finalized, %d already final, in %s\n", finalized, skipped,
               out_dir.c_str());
  return {};
}

}  // namespace
}  // namespace gdvr

int main(int argc, char** argv) {
  gdvr::retain_freed_memory_for_reuse();  // core/util/memory_tuning.h: batch tool
  using namespace gdvr;
  if (argc < 2) return usage(nullptr);
  const std::string verb = argv[1];
  if (verb == "-h" || verb == "--help") return usage(nullptr);
  if (verb != "render" && verb != "finalize" && verb != "chunks" && verb != "status" && verb != "tiles")
    return usage(("unknown command " + verb).c_str());

  std::string job_path, buffers_dir, out_dir, ocio_config, tiles_flag;
  long long tiles_per_task = 1;
  FrameSelection sel;
  bool chunk_index_set = false, video = false;
  int threads = 0;
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    // --name=value, as Kubernetes manifests write flags (deploy/k8s), is --name value.
    std::optional<std::string> inline_value;
    if (const size_t eq = a.find('='); a.rfind("--", 0) == 0 && eq != std::string::npos) {
      inline_value = a.substr(eq + 1);
      a = a.substr(0, eq);
    }
    auto next = [&](const char* name) -> std::string {
      if (inline_value) return *std::exchange(inline_value, std::nullopt);
      if (i + 1 >= argc) {
        usage((std::string(name) + " needs a value").c_str());
        std::exit(kExitUsage);
      }
      return argv[++i];
    };
    long long v = 0;
    if (a == "--frames")
      sel.frames = next("--frames");
    else if (a == "--buffers")
      buffers_dir = next("--buffers");
    else if (a == "--out")
      out_dir = next("--out");
    else if (a == "--video")
      video = true;
    else if (a == "--ocio-config")
      ocio_config = next("--ocio-config");
    else if (a == "--tiles")
      tiles_flag = next("--tiles");
    else if (a == "--tiles-per-task") {
      if (!parse_int(next("--tiles-per-task"), 1, INT_MAX, &v)) return usage("--tiles-per-task: expected a positive integer");
      tiles_per_task = v;
    }
    else if (a == "--threads") {
      if (!parse_int(next("--threads"), 1, 1024, &v)) return usage("--threads: expected 1..1024");
      threads = int(v);
    } else if (a == "--chunk-size") {
      if (!parse_int(next("--chunk-size"), 1, INT_MAX, &v)) return usage("--chunk-size: expected a positive integer");
      sel.chunk_size = v;
    } else if (a == "--chunk-index") {
      if (!parse_int(next("--chunk-index"), 0, INT_MAX, &v))
        return usage("--chunk-index: expected a non-negative integer");
      sel.chunk_index = v;
      chunk_index_set = true;
    } else if (a == "-h" || a == "--help")
      return usage(nullptr);
    else if (!a.empty() && a[0] == '-')
      return usage(("unknown option " + a).c_str());
    else if (job_path.empty())
      job_path = a;
    else
      return usage(("unexpected argument " + a).c_str());
    if (inline_value) return usage((a + " takes no value").c_str());
  }
  if (job_path.empty()) return usage("no job file given");
  if (!tiles_flag.empty() && verb != "finalize") return usage("--tiles belongs to finalize");
  if (verb == "chunks") {
    if (sel.chunk_size <= 0) return usage("chunks: --chunk-size N is required");
  } else if (verb == "tiles") {
  } else {
    if (buffers_dir.empty()) return usage("--buffers DIR is required");
    if (verb == "finalize" && out_dir.empty()) return usage("finalize: --out OUT is required");
    if (verb == "status" && video) return usage("status: --video belongs to finalize");
    if (verb == "render" && !out_dir.empty()) return usage("render: --out belongs to finalize");
    if (verb == "render" && video) return usage("render: --video belongs to finalize");
    if (chunk_index_set != (sel.chunk_size > 0)) return usage("--chunk-size and --chunk-index go together");
    if (chunk_index_set && !sel.frames.empty()) return usage("give --frames or --chunk-size/--chunk-index, not both");
  }

  auto job = load_job(job_path);
  if (!job.ok()) {
    std::fprintf(stderr, "gdvr-farm: %s\n", job.status().to_string().c_str());
    return kExitFailed;
  }
  if (verb == "chunks") {
    const auto& frames = job->frames;
    for (size_t b = 0; b < frames.size(); b += size_t(sel.chunk_size)) {
      std::vector<int> chunk(frames.begin() + b, frames.begin() + std::min(frames.size(), b + size_t(sel.chunk_size)));
      std::printf("%s\n", format_frames(chunk).c_str());
    }
    return 0;
  }
  if (verb == "tiles") {
    // The tile ranges of a tiled finalize, one task's per line: the grid of
    // the job's reconstruction (reconstruction.tile_size) at its resolution.
    auto resolved = resolve_job(job->spec, job->options);
    if (!resolved.ok()) {
      std::fprintf(stderr, "gdvr-farm: %s\n", resolved.status().to_string().c_str());
      return kExitFailed;
    }
    auto finalizer = JobFinalizer::create(job->spec);
    auto grid = finalizer.ok() ? finalizer.value()->tile_grid(int(resolved->width.value), int(resolved->height.value))
                               : Expected<TileGrid>(finalizer.status());
    if (grid.status().code() == StatusCode::kUnimplemented) {
      std::printf("0\n");  // no window solve: one task, which does nothing (see finalize --tiles)
      return 0;
    }
    if (!grid.ok()) {
      std::fprintf(stderr, "gdvr-farm tiles: %s\n", grid.status().to_string().c_str());
      return kExitFailed;
    }
    for (long long b = 0; b < grid->count(); b += tiles_per_task) {
      const long long last = std::min<long long>(grid->count(), b + tiles_per_task) - 1;
      if (last == b) std::printf("%lld\n", b);
      else std::printf("%lld-%lld\n", b, last);
    }
    return 0;
  }
  auto frames = select_frames(job.value(), sel);
  if (!frames.ok()) {
    std::fprintf(stderr, "gdvr-farm: %s\n", frames.status().to_string().c_str());
    return kExitUsage;
  }

  if (verb == "status") {
    // What a finalize stage (or a person) waits on: prints the frames whose
    // buffers are not complete yet; exit 0 when there are none.
    std::vector<int> missing;
    for (int f : frames.value()) {
      BufferCheck c = check_buffers(job.value(), buffers_dir, f);
      if (c.state == BufferState::kForeign) {
        std::fprintf(stderr, "gdvr-farm status: frame %d: %s\n", f, c.why.c_str());
        return kExitFailed;
      }
      if (c.state == BufferState::kMissing) missing.push_back(f);
    }
    std::printf("%zu of %zu frame(s) rendered%s%s\n", frames->size() - missing.size(), frames->size(),
                missing.empty() ? "" : "; missing: ", format_frames(missing).c_str());
    if (!missing.empty() || out_dir.empty()) return missing.empty() ? 0 : kExitMissingBuffers;
    // With --out: what the assembling finalize waits on after the tile
    // tasks: every frame final or with all its tile parts (integrators
    // without tiles: nothing more to wait for).
    auto finalizer = JobFinalizer::create(job->spec);
    auto resolved = resolve_job(job->spec, job->options);
    if (!finalizer.ok() || !resolved.ok()) {
      std::fprintf(stderr, "gdvr-farm status: %s\n",
                   (finalizer.ok() ? resolved.status() : finalizer.status()).to_string().c_str());
      return kExitFailed;
    }
    auto grid = finalizer.value()->tile_grid(int(resolved->width.value), int(resolved->height.value));
    if (grid.status().code() == StatusCode::kUnimplemented) return 0;
    if (!grid.ok()) {
      std::fprintf(stderr, "gdvr-farm status: %s\n", grid.status().to_string().c_str());
      return kExitFailed;
    }
    std::vector<int> untiled;
    std::error_code ec;
    for (int f : frames.value())
      if (!fs::exists(fs::path(out_dir) / frame_file_name(f), ec) && !missing_tile_parts(out_dir, f, *grid).empty())
        untiled.push_back(f);
    std::printf("%zu of %zu frame(s) final or with all %d tiles%s%s\n", frames->size() - untiled.size(),
                frames->size(), grid->count(), untiled.empty() ? "" : "; missing tiles: ", format_frames(untiled).c_str());
    return untiled.empty() ? 0 : kExitMissingBuffers;
  }

  // Farm managers stop a task with SIGTERM (then SIGKILL): stop at the next
  // tile; finished frames are already on disk.
  gdvr::tools::install_interrupt_handlers();
  Failure result;
  if (verb == "render") {
    result = cmd_render(job.value(), frames.value(), buffers_dir, threads);
  } else if (!tiles_flag.empty()) {
    if (video) return usage("--video belongs to the finalize that assembles the tiles");
    auto tiles = parse_frame_range(tiles_flag);
    if (!tiles.ok()) return usage(("--tiles: " + tiles.status().message()).c_str());
    result = cmd_finalize_tiles(job.value(), frames.value(), tiles.value(), buffers_dir, out_dir);
  } else {
    result = cmd_finalize(job.value(), frames.value(), buffers_dir, out_dir, video, ocio_config);
  }
  if (result.failed()) {
    std::fprintf(stderr, "gdvr-farm %s: %s\n", verb.c_str(), result.message.c_str());
    return result.exit_code;
  }
  return 0;
}
