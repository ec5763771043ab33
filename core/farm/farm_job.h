// A job as the farm's commands see it: the job file, its frames, and the
// fingerprint that ties buffers to it.
#pragma once

#include <string>
#include <vector>

#include "core/job/job_runner.h"
#include "core/job/job_spec.h"
#include "core/util/status.h"

namespace gdvr::farm {

struct FarmJob {
  std::string path;
  JobSpec spec;
  JobRunOptions options;
  std::vector<int> frames;  // the job's whole range
  std::string fingerprint;  // of everything the buffers depend on
};

// Reads and parses a job file; the scene path is relative to the file.
Expected<FarmJob> load_job(const std::string& path);

// What the render stage's output depends on: the job minus the fields only
// finalize or the server read, plus the scene file's bytes. Buffers from a
// different fingerprint are never mixed into a job.
std::string render_fingerprint(const JobSpec& job, const std::string& scene_bytes);

struct FrameSelection {
  std::string frames;  // --frames, empty: the job's (or the chunk's)
  long long chunk_size = 0, chunk_index = -1;
};

// The job frames a command works on: --frames intersected with the job's
// range (a farm's chunk of a stepped range may name frames the job skips),
// or the --chunk-index'th run of --chunk-size job frames.
Expected<std::vector<int>> select_frames(const FarmJob& job, const FrameSelection& sel);

// "0-5,7,9-11": the compact render-farm form of a sorted frame list.
std::string format_frames(const std::vector<int>& frames);

}  // namespace gdvr::farm
