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
