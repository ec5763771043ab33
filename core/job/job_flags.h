// The command line of the tools that run one job (gdvr-render, gdvr-report):
// the input, a job file or a scene, and the flags that override the job's
// fields, parsed alike and with the same messages in both. A flag's value is
// checked for its form here; the job the flags produce is checked as every
// job is, by validate() (core/job/job_validation.h).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "core/job/job_spec.h"
#include "core/util/status.h"

namespace gdvr::tools {

// Which of the flags a tool offers. Every tool takes the input, --out,
// --threads, --frames, --width, --height, --seed and --param (-D).
struct JobFlagSet {
  bool sampling = false;    // --spp, --time-budget
  bool integrator = false;  // --integrator, --shift, --temporal-shift, --recon, --alpha, --window, --tile-size, --keep-negative, --data-term
  bool outputs = false;     // --exr-compression
};

struct JobFlags {
  std::string input;    // JOB.json, or a scene (rendered with the job defaults)
  std::string out_dir;  // --out
  int threads = 0;      // --threads; 0: all cores

  // ---- Overrides of the job file's fields ----
  std::optional<std::string> frames;
  std::optional<int> width, height;
  // Sampling: either flag replaces both of the job file's spp and
  // time_budget_s (--time-budget alone: to the budget in the job's pass size
  // of 1 spp; both: passes of --spp).
  std::optional<int> spp;
  std::optional<double> time_budget_s;
  std::optional<uint64_t> seed;
  // Checked with the job, as the job file's field is: an unknown integrator
  // is the job's error, not a malformed flag.
  std::optional<std::string> integrator;
  std::optional<ShiftMapping> shift;
  std::optional<TemporalShiftMapping> temporal_shift;
  std::optional<ReconMethod> recon;
  std::optional<double> alpha;
  std::optional<int> window;
  std::optional<int> tile_size;  // --tile-size: reconstruction.tile_size
  bool keep_negative = false;  // reconstruction.clamp_negative = false
  std::optional<DataTerm> data_term;  // --data-term: reconstruction.data_term
  std::optional<std::string> exr_compression;  // --exr-compression: outputs.exr_compression (checked with the job)
  std::map<std::string, std::string> params;
};

// Takes argv[*i] when it is one of `offered` or the input (the first
// argument without a leading '-'): fills `flags`, moves *i past the flag's
// value and returns true. False: the argument is not one of these (the
// tool's own, or unknown). An error names the flag and what it expects.
Expected<bool> take_job_flag(int argc, char** argv, int* i, JobFlagSet offered, JobFlags* flags);

// The job the flags describe: the input job file (relative scene paths then
// resolve in its folder, returned in *base_dir; empty for a scene input)
// with the overrides applied, validated.
Expected<JobSpec> job_from_flags(const JobFlags& flags, std::string* base_dir);

}  // namespace gdvr::tools
