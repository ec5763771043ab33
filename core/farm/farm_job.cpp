#include "core/farm/farm_job.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>

#include "core/io/atomic_file.h"

namespace gdvr::farm {
namespace fs = std::filesystem;

namespace {

// 64-bit FNV-1a: stable across builds and machines, unlike std::hash.
uint64_t fnv1a(const std::string& bytes, uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return h;
}

}  // namespace

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
  auto text = read_text_file(path);
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
  auto scene_bytes = read_text_file(scene.string());
  if (!scene_bytes.ok()) return not_found(path + ": job.scene: cannot read '" + scene.string() + "'");
  job.fingerprint = render_fingerprint(job.spec, scene_bytes.value());
  return job;
}

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

}  // namespace gdvr::farm
