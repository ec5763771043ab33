// Inputs found by fuzz_job_spec (tests/fuzz/) that crashed parse_job_json.
#include <gtest/gtest.h>

#include <string>

#include "core/job/job_runner.h"
#include "core/job/job_spec.h"

namespace gdvr {
namespace {

// nlohmann::json throws out_of_range (not parse_error) for a number beyond
// double's range; it escaped parse_job_json: std::terminate.
TEST(JobSpecFuzzRegressionTest, NumberOverflowIsAnInvalidJsonError) {
  for (const std::string& text :
       {std::string("{\"fps\": 1E99999}"), std::string("999999999E99999"),
        std::string("999999999E99999\x01\x00\x00\x00\x00\xff\xff\xff\xff\xff\xff\xff\xff\xf6", 29)}) {
    Expected<JobSpec> job = Status(StatusCode::kInternal, "not run");
    ASSERT_NO_THROW(job = parse_job_json(text, "overflow.json"));
    ASSERT_FALSE(job.ok());
    EXPECT_EQ(job.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(job.status().message().find("overflow.json"), std::string::npos);
  }
}

// A keyframe's translate/rotate/scale (or lookat) whose matrix the 'matrix'
// form would reject (here a scale of 1.1e20 next to 1: condition 1e20) parsed,
// and job_to_json then printed a job that did not parse again. Every form now
// passes the same test; what parses prints to JSON that parses.
TEST(JobSpecFuzzRegressionTest, IllConditionedKeyIsRejectedInEveryForm) {
  const std::string key_scale =
      R"({"scene": "a.xml", "tracks": [{"target": "box", "keys": [{"frame": 0, "scale": [111111111111111111111, 1, 1]}]}]})";
  auto job = parse_job_json(key_scale, "scale.json");
  ASSERT_FALSE(job.ok());
  EXPECT_NE(job.status().message().find("job.tracks[0].keys[0]"), std::string::npos) << job.status().message();
  EXPECT_NE(job.status().message().find("ill-conditioned"), std::string::npos) << job.status().message();
  // A large but well-conditioned scale still parses and round-trips.
  auto fine = parse_job_json(
      R"({"scene": "a.xml", "tracks": [{"target": "box", "keys": [{"frame": 0, "scale": [1e6, 1e6, 1e6]}]}]})", "fine.json");
  ASSERT_TRUE(fine.ok()) << fine.status().to_string();
  auto again = parse_job_json(job_to_json(*fine), "again.json");
  EXPECT_TRUE(again.ok()) << again.status().to_string();
}

// The glTF finding's sibling in the job runner (found by reading, not by a
// fuzz target): a scene name too long for a path made
// std::filesystem::weakly_canonical / exists throw out of validate_job and
// run_job, which the server calls on every submitted job.
TEST(JobSpecFuzzRegressionTest, SceneNameTooLongForAPathIsAnError) {
  JobSpec job;
  job.scene = std::string(5000, 'a') + ".xml";
  for (const std::string& root : {std::string(), std::string(GDVR_SOURCE_DIR) + "/scenes"}) {
    JobRunOptions options;
    options.asset_root = root;
    options.base_dir = std::string(GDVR_SOURCE_DIR) + "/scenes";
    Status st;
    ASSERT_NO_THROW(st = validate_job(job, options)) << "asset root '" << root << "'";
    EXPECT_FALSE(st.ok());
  }
}

}  // namespace
}  // namespace gdvr
