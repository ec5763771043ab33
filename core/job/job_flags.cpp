#include "core/job/job_flags.h"

#include <filesystem>
#include <limits>

#include "core/io/atomic_file.h"
#include "core/job/job_validation.h"
#include "core/util/cli_args.h"

namespace gdvr::tools {
namespace {

// One flag's value in [lo, hi], or a message naming the flag and the range.
Expected<int> int_value(const std::string& flag, const std::string& text, int lo, int hi) {
  long long v = 0;
  if (!parse_int(text, lo, hi, &v))
    return invalid_argument(flag + ": expected " + std::to_string(lo) + ".." + std::to_string(hi));
  return int(v);
}

}  // namespace

Expected<bool> take_job_flag(int argc, char** argv, int* i, JobFlagSet offered, JobFlags* flags) {
  const std::string a = argv[*i];
  if (a.empty() || a[0] != '-') {
    if (!flags->input.empty()) return invalid_argument("unexpected argument " + a);
    flags->input = a;
    return true;
  }
  const bool sampling = offered.sampling && (a == "--spp" || a == "--time-budget");
  const bool integrator = offered.integrator && (a == "--integrator" || a == "--shift" || a == "--temporal-shift" ||
                                                 a == "--recon" || a == "--alpha" || a == "--window" ||
                                                 a == "--tile-size" || a == "--data-term");
  const bool outputs = offered.outputs && a == "--exr-compression";
  const bool common = a == "--out" || a == "--threads" || a == "--frames" || a == "--width" || a == "--height" ||
                      a == "--seed" || a == "--param" || a == "-D";
  if (offered.integrator && a == "--keep-negative") {
    flags->keep_negative = true;
    return true;
  }
  if (!sampling && !integrator && !outputs && !common) return false;
  if (*i + 1 >= argc) return invalid_argument(a + " needs a value");
  const std::string value = argv[++*i];

  auto set_int = [&](int lo, int hi, std::optional<int>* out) -> Expected<bool> {
    auto v = int_value(a, value, lo, hi);
    if (!v.ok()) return v.status();
    *out = v.value();
    return true;
  };
  auto set_name = [&](const auto& names, auto* out) -> Expected<bool> {
    auto v = parse_enum_name(names, value, a.c_str());
    if (!v.ok()) return v.status();
    *out = v.value();
    return true;
  };
  if (a == "--out") flags->out_dir = value;
  else if (a == "--frames") flags->frames = value;
  else if (a == "--threads") {
    auto v = int_value(a, value, 1, 1024);
    if (!v.ok()) return v.status();
    flags->threads = v.value();
  } else if (a == "--width") return set_int(1, kMaxJobResolution, &flags->width);
  else if (a == "--height") return set_int(1, kMaxJobResolution, &flags->height);
  else if (a == "--spp") return set_int(1, kMaxJobSpp, &flags->spp);
  else if (a == "--window") return set_int(1, kMaxWindowFrames, &flags->window);
  else if (a == "--tile-size") return set_int(0, kMaxJobResolution, &flags->tile_size);
  else if (a == "--seed") {
    long long v = 0;
    if (!parse_int(value, 0, 1LL << 62, &v)) return invalid_argument("--seed: expected a non-negative integer");
    flags->seed = uint64_t(v);
  } else if (a == "--time-budget") {
    double v = 0;
    if (!parse_number(value, 0, 1e9, &v) || !(v > 0))
      return invalid_argument("--time-budget: expected a positive number of seconds");
    flags->time_budget_s = v;
  } else if (a == "--alpha") {
    double v = 0;
    if (!parse_number(value, 0, std::numeric_limits<double>::max(), &v))
      return invalid_argument("--alpha: expected a finite number >= 0");
    flags->alpha = v;
  } else if (a == "--param" || a == "-D") {
    if (!parse_param(value, &flags->params)) return invalid_argument("--param: expected NAME=VALUE");
  } else if (a == "--integrator") {
    flags->integrator = value;
  } else if (a == "--shift") return set_name(kShiftMappingNames, &flags->shift);
  else if (a == "--temporal-shift") return set_name(kTemporalShiftNames, &flags->temporal_shift);
  else if (a == "--recon") return set_name(kReconMethodNames, &flags->recon);
  else if (a == "--data-term") return set_name(kDataTermNames, &flags->data_term);
  else if (a == "--exr-compression") flags->exr_compression = value;
  return true;
}

Expected<JobSpec> job_from_flags(const JobFlags& flags, std::string* base_dir) {
  namespace fs = std::filesystem;
  JobSpec job;
  base_dir->clear();
  if (fs::path(flags.input).extension() == ".json") {
    auto text = read_text_file(flags.input);
    if (!text.ok()) return text.status();
    auto parsed = parse_job_json(text.value(), flags.input);
    if (!parsed.ok()) return parsed.status();
    job = std::move(parsed.value());
    *base_dir = fs::absolute(flags.input).parent_path().string();
  } else {
    job.scene = fs::absolute(flags.input).string();
  }
  if (flags.frames) job.frames = *flags.frames;
  if (flags.width) job.width = *flags.width;
  if (flags.height) job.height = *flags.height;
  // The command line's sampling replaces the job file's: --time-budget alone
  // renders to the budget whatever spp the file names, --spp alone renders
  // that many samples whatever budget the file names, and both together make
  // --spp the budget's pass size (docs/service.md, "Samples and time budgets").
  if (flags.spp || flags.time_budget_s) {
    job.spp = flags.spp.value_or(0);
    job.time_budget_s = flags.time_budget_s.value_or(0);
  }
  if (flags.seed) job.seed = *flags.seed;
  if (flags.integrator) {
    auto integrator = parse_integrator(*flags.integrator);
    if (!integrator.ok()) return integrator.status().with_context("job.");
    job.integrator = integrator.value();
  }
  if (flags.shift) job.shift = *flags.shift;
  if (flags.temporal_shift) job.temporal_shift = *flags.temporal_shift;
  if (flags.recon) job.reconstruction.method = *flags.recon;
  if (flags.alpha) job.reconstruction.alpha = *flags.alpha;
  if (flags.window) job.reconstruction.window = *flags.window;
  if (flags.tile_size) job.reconstruction.tile_size = *flags.tile_size;
  if (flags.keep_negative) job.reconstruction.clamp_negative = false;
  if (flags.data_term) job.reconstruction.data_term = *flags.data_term;
  if (flags.exr_compression) job.outputs.exr_compression = *flags.exr_compression;
  for (const auto& [name, value] : flags.params) job.params[name] = value;
  GDVR_RETURN_IF_ERROR(validate(job));
  return job;
}

}  // namespace gdvr::tools
