// libFuzzer target: the job-spec parser (parse_job_json) and the frame-range
// syntax (parse_frame_range). Invariants: a parsed job prints (job_to_json)
// to JSON that parses again to the same JSON; a parsed frame list is sorted,
// distinct, non-negative and within the limit.
#include <string>

#include "core/job/job_spec.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > gdvr::fuzz::kMaxInput) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto job = gdvr::parse_job_json(text, "fuzz.json");
  if (job.ok()) {
    const std::string printed = gdvr::job_to_json(job.value());
    auto again = gdvr::parse_job_json(printed, "printed.json");
    gdvr::fuzz::check(again.ok(), "job_to_json output parses again");
    if (again.ok()) gdvr::fuzz::check(gdvr::job_to_json(again.value()) == printed, "job JSON round trip is stable");
  }
  // The same bytes as a frame range (short ones: the syntax is short).
  if (size <= 256) {
    auto frames = gdvr::parse_frame_range(text, /* max_frames = */ 10000);
    if (frames.ok()) {
      const std::vector<int>& f = frames.value();
      gdvr::fuzz::check(!f.empty() && f.size() <= 10000, "frame count within the limit");
      for (size_t i = 0; i < f.size(); ++i) {
        gdvr::fuzz::check(f[i] >= 0, "frames are non-negative");
        if (i) gdvr::fuzz::check(f[i - 1] < f[i], "frames sorted and distinct");
      }
    }
  }
  return 0;
}
