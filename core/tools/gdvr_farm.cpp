// gdvr-farm: the two stages of a job as commands a render-farm manager
// (OpenCue, Deadline, Flamenco, a Kubernetes Indexed Job, a shell loop) can
// schedule on any number of machines sharing one folder. gdvr does not become
// a scheduler: it only makes each command idempotent and restartable.
//
//   gdvr-farm render   JOB.json (--frames A-B | --chunk-size N --chunk-index I) --buffers DIR [--threads N]
//   gdvr-farm finalize JOB.json [--frames A-B] --buffers DIR --out OUT [--video] [--ocio-config PATH]
//   gdvr-farm chunks   JOB.json --chunk-size N      one chunk per line, render-farm syntax
//   gdvr-farm status   JOB.json [--frames A-B] --buffers DIR   exit 0 once all buffers are complete
//
// render writes DIR/buffers_0001.exr (every pre-reconstruction layer, float)
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
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/io/image_io.h"
#include "core/job/job_outputs.h"
#include "core/job/job_runner.h"
#include "core/job/job_spec.h"
#include "core/tools/cli_args.h"
#include "core/util/memory_tuning.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;
constexpr int kExitMissingBuffers = 3;
constexpr int kExitCancelled = 130;

std::atomic<bool> g_cancel{false};
void on_signal(int) { g_cancel = true; }

int usage(const char* msg) {
  if (msg) std::fprintf(stderr, "gdvr-farm: %s\n", msg);
  std::fprintf(stderr,
               "usage: gdvr-farm render JOB.json (--frames A-B | --chunk-size N --chunk-index I) --buffers DIR\n"
               "                 [--threads N]\n"
               "       gdvr-farm finalize JOB.json [--frames A-B | --chunk-size N --chunk-index I] --buffers DIR\n"
               "                 --out OUT [--video] [--ocio-config PATH]\n"
               "       gdvr-farm chunks JOB.json --chunk-size N\n"
               "       gdvr-farm status JOB.json [--frames A-B] --buffers DIR\n"
               "Frames use render-farm syntax (\"1-100\", \"1-100x2\", \"1,5,10-20\") and default to the job's.\n"
               "exit codes: 0 done, 1 failed, 2 usage, 3 buffers missing, 130 cancelled\n");
  return kExitUsage;
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

std::string numbered(const char* pattern, int frame) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), pattern, frame);
  return buf;
}
std::string buffers_exr_name(int frame) { return numbered("buffers_%04d.exr", frame); }
std::string buffers_json_name(int frame) { return numbered("buffers_%04d.json", frame); }
// A finalized frame's stats.json entry, kept beside the buffers (which every
// task shares) so the last finalize lists the whole job's frames.
std::string final_stats_name(int frame) { return numbered("final_%04d.json", frame); }

// "0-5,7,9-11": the compact render-farm form of a sorted frame list.
std::string format_frames(const std::vector<int>& frames) {
  std::string s;
  for (size_t i = 0; i < frames.size();) {
    size_t j = i;
    while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1) ++j;
    if (!s.empty()) s += ",";
    s += std::to_string(frames[i]);
    if (j > i) s += "-" + std::to_string(frames[j]);
    i = j + 1;
  }
  return s;
}

Expected<std::string> read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(path + ": cannot read");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// ---- Files other machines may be writing too ----
// core's writers name their temporary "<file>.tmp.<pid>", unique on one
// machine only. On shared storage a retried chunk can overlap the attempt it
// replaces (a pre-empted worker that is not dead yet), and two machines can
// have equal pids, so farm files are staged under a hidden name that also
// carries the host, then renamed into place: readers see either no file or a
// complete one, and concurrent writers of one frame never share a temporary.

std::string host_name() {
  char buf[HOST_NAME_MAX + 1] = {};
  if (gethostname(buf, sizeof(buf) - 1) != 0 || buf[0] == '\0') return "host";
  std::string h(buf);
  for (char& c : h)
    if (c == '/' || c == '.') c = '_';  // dots separate fields of the staging name
  return h;
}

const std::string& staging_tag() {
  static const std::string tag = host_name() + "." + std::to_string(long(getpid()));
  return tag;
}

// ".buffers_0001.exr.<host>.<pid>.staging" beside `path`.
std::string staging_path_for(const std::string& path) {
  fs::path p(path);
  return (p.parent_path() / ("." + p.filename().string() + "." + staging_tag() + ".staging")).string();
}

Status write_exr_shared(const std::string& path, const LayeredImage& image) {
  const std::string staged = staging_path_for(path);
  GDVR_RETURN_IF_ERROR(write_exr(staged, image));
  return commit_temporary(staged, path);
}

Status write_text_shared(const std::string& path, const std::string& text) {
  const std::string staged = staging_path_for(path);
  {
    std::ofstream out(staged, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) {
      discard_temporary(staged);
      return internal_error(path + ": cannot write '" + staged + "'");
    }
  }
  return commit_temporary(staged, path);
}

// Removes staging files that this host's dead processes left behind (a
// worker killed mid-write). Files of other hosts are left alone: their
// writers may still be running; docs/farm.md says how to sweep them.
void remove_own_stale_staging(const std::string& dir) {
  const std::string host = host_name();
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    // ".<file>.<host>.<pid>.staging" (+ ".tmp.<host>.<pid>" while core writes
    // it), or core's own "<file>.tmp.<host>.<pid>" (the output stage's frames
    // and previews).
    const std::string marker = "." + host + ".";
    const bool staging = !name.empty() && name[0] == '.' && name.find(".staging") != std::string::npos;
    const bool core_temporary = name.find(".tmp" + marker) != std::string::npos;
    if (!staging && !core_temporary) continue;
    size_t at = name.rfind(marker);
    if (at == std::string::npos) continue;
    long long pid = 0;
    size_t pid_begin = at + marker.size(), pid_end = std::min(name.find('.', pid_begin), name.size());
    if (!parse_int(name.substr(pid_begin, pid_end - pid_begin), 1, INT_MAX, &pid)) continue;
    if (pid == getpid()) continue;
    if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to judge)
    fs::remove(entry.path(), ec);
  }
}

// ---- The job ----

// 64-bit FNV-1a: stable across builds and machines, unlike std::hash.
uint64_t fnv1a(const std::string& bytes, uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return h;
}

struct FarmJob {
  std::string path;
  JobSpec spec;
  JobRunOptions options;
  std::vector<int> frames;  // the job's whole range
  std::string fingerprint;  // of everything the buffers depend on
};

// What the render stage's output depends on: the job minus the fields only
// finalize or the server read, plus the scene file's bytes. Buffers from a
// different fingerprint are never mixed into a job.
std::string render_fingerprint(const JobSpec& job, const std::string& scene_bytes) {
  JobSpec j = job;
  j.frames = "0";
  j.reconstruction = ReconstructionSpec();
  j.outputs = OutputSpec();
  j.priority = 0;
  j.reference.clear();
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", (unsigned long long)fnv1a(scene_bytes, fnv1a(job_to_json(j))));
  return buf;
}

Expected<FarmJob> load_job(const std::string& path) {
  auto text = read_text(path);
  if (!text.ok()) return text.status();
  auto parsed = parse_job_json(text.value(), path);
  if (!parsed.ok()) return parsed.status();
  FarmJob job;
  job.path = path;
  job.spec = std::move(parsed.value());
  job.options.base_dir = fs::absolute(path).parent_path().string();
  auto frames = parse_frame_range(job.spec.frames);
  if (!frames.ok()) return frames.status().with_context(path + ": job.frames: ");
  job.frames = std::move(frames.value());
  if (job.frames.empty()) return invalid_argument(path + ": job.frames selects no frame");
  fs::path scene(job.spec.scene);
  if (scene.is_relative()) scene = fs::path(job.options.base_dir) / scene;
  auto scene_bytes = read_text(scene.string());
  if (!scene_bytes.ok()) return not_found(path + ": job.scene: cannot read '" + scene.string() + "'");
  job.fingerprint = render_fingerprint(job.spec, scene_bytes.value());
  return job;
}

struct FrameSelection {
  std::string frames;  // --frames, empty: the job's (or the chunk's)
  long long chunk_size = 0, chunk_index = -1;
};

// The job frames a command works on: --frames intersected with the job's
// range (a farm's chunk of a stepped range may name frames the job skips),
// or the --chunk-index'th run of --chunk-size job frames.
Expected<std::vector<int>> select_frames(const FarmJob& job, const FrameSelection& sel) {
  if (sel.chunk_size > 0) {
    const size_t begin = size_t(sel.chunk_index) * size_t(sel.chunk_size);
    if (begin >= job.frames.size())
      return invalid_argument("--chunk-index " + std::to_string(sel.chunk_index) + " is past the last chunk (" +
                              std::to_string((job.frames.size() + sel.chunk_size - 1) / sel.chunk_size) +
                              " chunks of " + std::to_string(sel.chunk_size) + " frames)");
    const size_t end = std::min(job.frames.size(), begin + size_t(sel.chunk_size));
    return std::vector<int>(job.frames.begin() + begin, job.frames.begin() + end);
  }
  if (sel.frames.empty()) return job.frames;
  auto wanted = parse_frame_range(sel.frames);
  if (!wanted.ok()) return wanted.status().with_context("--frames: ");
  const std::set<int> in_job(job.frames.begin(), job.frames.end());
  std::vector<int> out;
  for (int f : wanted.value())
    if (in_job.count(f)) out.push_back(f);
  if (out.empty())
    return invalid_argument("--frames " + sel.frames + ": none of these frames is in the job's range '" +
                            job.spec.frames + "'");
  return out;
}

// ---- Buffer files ----

// A frame's render statistics, kept in its buffers marker: the stats.json
// entry form (core/job/job_outputs.h) without a file.
json stats_to_json(const FrameStats& s) { return json::parse(frame_entry_json({"", 0, s})); }

FrameStats stats_from_json(const json& j) {
  auto entry = parse_frame_entry(j.dump());
  return entry.ok() ? entry->stats : FrameStats{};
}

enum class BufferState { kMissing, kComplete, kForeign };

struct BufferCheck {
  BufferState state = BufferState::kMissing;
  json marker;
  std::string why;  // for kMissing/kForeign: what is wrong
};

// A frame's buffers are complete when its JSON marker parses, names this
// job's fingerprint and the EXR beside it has the size the marker recorded
// (a file copied in half, or replaced by hand, does not pass).
BufferCheck check_buffers(const FarmJob& job, const std::string& dir, int frame) {
  BufferCheck c;
  const std::string exr = (fs::path(dir) / buffers_exr_name(frame)).string();
  const std::string marker = (fs::path(dir) / buffers_json_name(frame)).string();
  auto text = read_text(marker);
  if (!text.ok()) {
    std::error_code ec;
    c.why = fs::exists(exr, ec) ? "its marker " + marker + " is missing: the worker stopped before committing it"
                                : "not rendered yet";
    return c;
  }
  json j = json::parse(text.value(), nullptr, /* allow_exceptions = */ false);
  if (j.is_discarded() || !j.is_object() || !j.contains("fingerprint") || !j.contains("exr_bytes")) {
    c.why = marker + " is not a gdvr-farm buffers marker";
    return c;
  }
  if (j.value("fingerprint", std::string()) != job.fingerprint) {
    c.state = BufferState::kForeign;
    c.why = marker + " belongs to a different job or scene (fingerprint " + j.value("fingerprint", std::string()) +
            ", this job " + job.fingerprint + "); use a fresh --buffers folder";
    return c;
  }
  std::error_code ec;
  const auto size = fs::file_size(exr, ec);
  if (ec || size != j.value("exr_bytes", uint64_t(0))) {
    c.why = ec ? "no " + exr
               : exr + " is " + std::to_string(size) + " bytes, its marker says " +
                     std::to_string(j.value("exr_bytes", uint64_t(0)));
    return c;
  }
  c.state = BufferState::kComplete;
  c.marker = std::move(j);
  return c;
}

Status write_buffers(const FarmJob& job, const std::string& dir, const FrameBuffers& fb) {
  const std::string exr = (fs::path(dir) / buffers_exr_name(fb.frame)).string();
  GDVR_RETURN_IF_ERROR(write_exr_shared(exr, fb.layers));
  std::error_code ec;
  const auto size = fs::file_size(exr, ec);
  if (ec) return internal_error(exr + ": cannot stat after writing: " + ec.message());
  json marker = {{"frame", fb.frame},
                 {"job", job.path},
                 {"fingerprint", job.fingerprint},
                 {"exr", buffers_exr_name(fb.frame)},
                 {"exr_bytes", uint64_t(size)},
                 {"stats", stats_to_json(fb.stats)}};
  // The marker goes last: a worker killed between the two files leaves a
  // frame that counts as not rendered, and the retry writes it again.
  return write_text_shared((fs::path(dir) / buffers_json_name(fb.frame)).string(), marker.dump(2) + "\n");
}

Expected<FrameBuffers> read_buffers(const FarmJob& job, const std::string& dir, int frame, int for_frame) {
  BufferCheck c = check_buffers(job, dir, frame);
  const std::string exr = (fs::path(dir) / buffers_exr_name(frame)).string();
  const std::string context = "frame " + std::to_string(for_frame) +
                              (frame == for_frame ? "" : " (needs frame " + std::to_string(frame) + ")") + ": ";
  if (c.state == BufferState::kForeign) return failed_precondition(context + c.why);
  if (c.state == BufferState::kMissing)
    return not_found(context + "buffers missing: " + exr + " (" + c.why + "); render them first with " +
                     "gdvr-farm render " + job.path + " --frames " + std::to_string(frame) + " --buffers " + dir);
  auto layers = read_exr(exr);
  if (!layers.ok()) return layers.status().with_context(context);
  FrameBuffers fb;
  fb.frame = frame;
  fb.layers = std::move(layers.value());
  fb.stats = stats_from_json(c.marker.value("stats", json::object()));
  return fb;
}

// ---- render ----

Failure cmd_render(const FarmJob& job, const std::vector<int>& frames, const std::string& dir, int threads) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return fail(kExitFailed, "--buffers: cannot create '" + dir + "': " + ec.message());
  remove_own_stale_staging(dir);

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

// stats.json in the output folder, as gdvr-render and the server write it:
// every frame of the job that is final there (by this task or an earlier
// one) with its statistics. Tasks finalizing chunks in parallel each write
// what they see; the last one to finish lists all.
Status write_job_stats(const FarmJob& job, const std::string& buffers_dir, const std::string& out_dir) {
  std::vector<WrittenFrame> final_frames;
  for (int f : job.frames) {
    std::error_code ec;
    const auto bytes = fs::file_size(fs::path(out_dir) / frame_file_name(f), ec);
    if (ec) continue;  // not final yet
    std::ifstream in(fs::path(buffers_dir) / final_stats_name(f), std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    auto entry = parse_frame_entry(text.str());
    // A missing or stale entry (the frame was written again since) is left
    // out rather than reported with the wrong figures.
    if (entry.ok() && entry->stats.frame == f && entry->bytes == bytes) final_frames.push_back(entry.value());
  }
  const bool complete = final_frames.size() == job.frames.size();
  const std::string text = stats_json(
      {{"job", job.path}, {"integrator", job.spec.integrator}, {"state", complete ? "completed" : "partial"}},
      int(job.frames.size()), final_frames);
  // A rerun that finalizes nothing leaves the folder untouched, mtimes included.
  const fs::path path = fs::path(out_dir) / "stats.json";
  std::ifstream old(path, std::ios::binary);
  std::stringstream old_text;
  old_text << old.rdbuf();
  if (old && old_text.str() == text) return Status::Ok();
  return write_text_atomic(path.string(), text);
}

Failure cmd_finalize(const FarmJob& job, const std::vector<int>& frames, const std::string& buffers_dir,
                     const std::string& out_dir, bool video, const std::string& ocio_flag) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) return fail(kExitFailed, "--out: cannot create '" + out_dir + "': " + ec.message());
  remove_own_stale_staging(out_dir);

  // Check every frame's inputs before the first output, so a finalize
  // scheduled too early fails at once and names everything still missing.
  std::set<int> needed;
  for (int f : frames)
    if (!fs::exists(fs::path(out_dir) / frame_file_name(f), ec))
      for (int n : frames_needed_to_finalize(job.spec, job.frames, f)) needed.insert(n);
  std::vector<std::string> missing;
  for (int n : needed) {
    BufferCheck c = check_buffers(job, buffers_dir, n);
    if (c.state == BufferState::kForeign) return fail(kExitFailed, "frame " + std::to_string(n) + ": " + c.why);
    if (c.state == BufferState::kMissing)
      missing.push_back("frame " + std::to_string(n) + ": " + (fs::path(buffers_dir) / buffers_exr_name(n)).string() +
                        " (" + c.why + ")");
  }
  if (!missing.empty()) {
    std::string msg = "buffers missing for " + std::to_string(missing.size()) + " frame(s); render them first:";
    for (const auto& m : missing) msg += "\n  " + m;
    return fail(kExitMissingBuffers, msg);
  }

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
    for (int n : frames_needed_to_finalize(job.spec, job.frames, f)) last_use[n] = f;

  // One finalizer for the task: a T-GPT window is solved once for all of the
  // task's frames it holds, not once per frame.
  auto finalizer = JobFinalizer::create(job.spec);
  if (!finalizer.ok()) return fail(finalizer.status());
  int finalized = 0, skipped = 0;
  for (int f : frames) {
    if (g_cancel) return fail(cancelled("cancelled"));
    if (fs::exists(fs::path(out_dir) / frame_file_name(f), ec)) {
      // Finalized by an earlier (perhaps killed) run: its preview and video
      // frame come from the EXR as written, so they are the same either way.
      ++skipped;
      if (Status st = outputs.value()->complete_earlier_frame(f); !st.ok()) return fail(st);
    } else {
      for (int n : frames_needed_to_finalize(job.spec, job.frames, f)) {
        if (loaded.count(n)) continue;
        auto fb = read_buffers(job, buffers_dir, n, f);
        if (!fb.ok())
          return fail(fb.status().code() == StatusCode::kNotFound ? kExitMissingBuffers : kExitFailed,
                      fb.status().to_string());
        loaded[n] = std::move(fb.value());
      }
      auto out = finalizer.value()->finalize(f, loaded);
      if (!out.ok()) return fail(out.status());
      auto written = outputs.value()->write_frame(out.value());
      if (!written.ok()) return fail(written.status());
      if (Status st = write_text_shared((fs::path(buffers_dir) / final_stats_name(f)).string(),
                                        frame_entry_json(written.value()) + "\n");
          !st.ok())
        return fail(st);
      ++finalized;
      std::fprintf(stderr, "frame %d: reconstruct %.2f s -> %s\n", f, out->stats.reconstruct_seconds,
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
  if (verb != "render" && verb != "finalize" && verb != "chunks" && verb != "status")
    return usage(("unknown command " + verb).c_str());

  std::string job_path, buffers_dir, out_dir, ocio_config;
  FrameSelection sel;
  bool chunk_index_set = false, video = false;
  int threads = 0;
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&](const char* name) -> std::string {
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
  }
  if (job_path.empty()) return usage("no job file given");
  if (verb == "chunks") {
    if (sel.chunk_size <= 0) return usage("chunks: --chunk-size N is required");
  } else {
    if (buffers_dir.empty()) return usage("--buffers DIR is required");
    if (verb == "finalize" && out_dir.empty()) return usage("finalize: --out OUT is required");
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
    return missing.empty() ? 0 : kExitMissingBuffers;
  }

  // Farm managers stop a task with SIGTERM (then SIGKILL): stop at the next
  // tile; finished frames are already on disk.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  Failure result = verb == "render"
                       ? cmd_render(job.value(), frames.value(), buffers_dir, threads)
                       : cmd_finalize(job.value(), frames.value(), buffers_dir, out_dir, video, ocio_config);
  if (result.failed()) {
    std::fprintf(stderr, "gdvr-farm %s: %s\n", verb.c_str(), result.message.c_str());
    return result.exit_code;
  }
  return 0;
}
