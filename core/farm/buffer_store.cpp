#include "core/farm/buffer_store.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/io/atomic_file.h"
#include "core/io/exr_region_file.h"
#include "core/io/image_io.h"
#include "core/job/job_outputs.h"

namespace gdvr::farm {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::string numbered(const char* pattern, int frame) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), pattern, frame);
  return buf;
}

// A frame's render statistics, kept in its buffers marker: the stats.json
// entry form (core/job/job_outputs.h) without a file.
json stats_to_json(const FrameStats& s) { return json::parse(frame_entry_json({"", 0, s})); }

FrameStats stats_from_json(const json& j) {
  auto entry = parse_frame_entry(j.dump());
  return entry.ok() ? entry->stats : FrameStats{};
}

}  // namespace

std::string buffers_exr_name(int frame) { return numbered("buffers_%04d.exr", frame); }
std::string buffers_json_name(int frame) { return numbered("buffers_%04d.json", frame); }
std::string final_stats_name(int frame) { return numbered("final_%04d.json", frame); }

BufferCheck check_buffers(const FarmJob& job, const std::string& dir, int frame) {
  BufferCheck c;
  const std::string exr = (fs::path(dir) / buffers_exr_name(frame)).string();
  const std::string marker = (fs::path(dir) / buffers_json_name(frame)).string();
  auto text = read_text_file(marker);
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
  c.stats = stats_from_json(j.value("stats", json::object()));
  return c;
}

Status write_buffers(const FarmJob& job, const std::string& dir, const FrameBuffers& fb) {
  const std::string exr = (fs::path(dir) / buffers_exr_name(fb.frame)).string();
  GDVR_RETURN_IF_ERROR(write_exr(exr, fb.layers));
  std::error_code ec;
  const auto size = fs::file_size(exr, ec);
  if (ec) return internal_error(exr + ": cannot stat after writing: " + ec.message());
  json marker = {{"frame", fb.frame},
                 {"job", job.path},
                 {"fingerprint", job.fingerprint},
                 {"exr", buffers_exr_name(fb.frame)},
                 {"exr_bytes", uint64_t(size)},
                 {"stats", stats_to_json(fb.stats)}};
  return write_text_atomic((fs::path(dir) / buffers_json_name(fb.frame)).string(), marker.dump(2) + "\n");
}

namespace {

// A frame's complete buffers, read whole or left in their EXR.
Expected<FrameBuffers> load_buffers(const FarmJob& job, const std::string& dir, int frame, int for_frame,
                                    bool whole) {
  BufferCheck c = check_buffers(job, dir, frame);
  const std::string exr = (fs::path(dir) / buffers_exr_name(frame)).string();
  const std::string context = "frame " + std::to_string(for_frame) +
                              (frame == for_frame ? "" : " (needs frame " + std::to_string(frame) + ")") + ": ";
  if (c.state == BufferState::kForeign) return failed_precondition(context + c.why);
  if (c.state == BufferState::kMissing)
    return not_found(context + "buffers missing: " + exr + " (" + c.why + "); render them first with " +
                     "gdvr-farm render " + job.path + " --frames " + std::to_string(frame) + " --buffers " + dir);
  FrameBuffers fb;
  fb.frame = frame;
  fb.stats = c.stats;
  if (whole) {
    auto layers = read_exr(exr);
    if (!layers.ok()) return layers.status().with_context(context);
    fb.layers = std::move(layers.value());
  } else {
    auto file = ExrRegionFile::open(exr);
    if (!file.ok()) return file.status().with_context(context);
    fb.on_disk = std::move(file.value());
  }
  return fb;
}

}  // namespace

Expected<FrameBuffers> read_buffers(const FarmJob& job, const std::string& dir, int frame, int for_frame) {
  return load_buffers(job, dir, frame, for_frame, /* whole = */ true);
}

Expected<FrameBuffers> open_buffers(const FarmJob& job, const std::string& dir, int frame, int for_frame) {
  return load_buffers(job, dir, frame, for_frame, /* whole = */ false);
}

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
      {{"job", job.path}, {"integrator", integrator_name(job.spec.integrator)}, {"state", complete ? "completed" : "partial"}},
      int(job.frames.size()), final_frames);
  // A rerun that finalizes nothing leaves the folder untouched, mtimes included.
  const fs::path path = fs::path(out_dir) / "stats.json";
  std::ifstream old(path, std::ios::binary);
  std::stringstream old_text;
  old_text << old.rdbuf();
  if (old && old_text.str() == text) return Status::Ok();
  return write_text_atomic(path.string(), text);
}

}  // namespace gdvr::farm
