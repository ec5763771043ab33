// The command line's sampling flags against a job file's spp and time budget
// (core/job/job_flags.h): the command line's sampling replaces the file's.
#include "core/job/job_flags.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/job/job_runner.h"

namespace gdvr::tools {
namespace {

namespace fs = std::filesystem;

// A job file of the demo scene naming `sampling` (e.g. "spp": 16), in a
// temporary folder, removed at the end of the test binary.
std::string job_file(const std::string& name, const std::string& sampling) {
  struct Cleanup {
    std::vector<fs::path> dirs;
    ~Cleanup() {
      std::error_code ignored;
      for (const fs::path& d : dirs) fs::remove_all(d, ignored);
    }
  };
  static Cleanup cleanup;
  const fs::path dir = fs::temp_directory_path() / ("gdvr_job_flags_" + name);
  fs::create_directories(dir);
  cleanup.dirs.push_back(dir);
  const fs::path path = dir / "job.json";
  const std::string scene = (fs::path(GDVR_SOURCE_DIR) / "scenes/demo/cbox_demo.xml").string();
  std::ofstream(path) << R"({"scene": ")" << scene << R"(", "frames": "0-1", "width": 8, "height": 8, )" << sampling
                      << "}\n";
  return path.string();
}

Expected<JobSpec> job_from_args(std::vector<std::string> args) {
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>("gdvr-render"));
  for (std::string& a : args) argv.push_back(a.data());
  JobFlags flags;
  for (int i = 1; i < int(argv.size()); ++i) {
    auto taken = take_job_flag(int(argv.size()), argv.data(), &i, {true, true, true}, &flags);
    if (!taken.ok()) return taken.status();
    if (!taken.value()) return invalid_argument(std::string("not a job flag: ") + argv[size_t(i)]);
  }
  std::string base_dir;
  return job_from_flags(flags, &base_dir);
}

TEST(JobFlagsTest, TimeBudgetAloneOverridesTheFilesSpp) {
  auto job = job_from_args({job_file("budget_alone", R"("spp": 16)"), "--time-budget", "0.5"});
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  EXPECT_EQ(job->time_budget_s, 0.5);
  EXPECT_EQ(job->spp, 0) << "the file's 16 spp would be the budget's pass size";
  // What it will render: passes of 1 spp to the budget.
  auto resolved = resolve_job(job.value(), JobRunOptions{});
  ASSERT_TRUE(resolved.ok()) << resolved.status().to_string();
  EXPECT_EQ(resolved->spp.value, 1);
  EXPECT_EQ(resolved->time_budget_s, 0.5);
}

TEST(JobFlagsTest, SppWithTimeBudgetIsThePassSize) {
  auto job = job_from_args({job_file("both", R"("spp": 16)"), "--time-budget", "2", "--spp", "4"});
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  EXPECT_EQ(job->time_budget_s, 2.0);
  EXPECT_EQ(job->spp, 4);
}

TEST(JobFlagsTest, SppAloneOverridesTheFilesBudget) {
  auto job = job_from_args({job_file("spp_alone", R"("time_budget_s": 3)"), "--spp", "8"});
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  EXPECT_EQ(job->spp, 8);
  EXPECT_EQ(job->time_budget_s, 0.0) << "--spp 8 renders 8 samples, not passes of 8 to the file's budget";
}

TEST(JobFlagsTest, WithoutSamplingFlagsTheFileDecides) {
  auto job = job_from_args({job_file("file", R"("spp": 16, "time_budget_s": 3)"), "--frames", "0"});
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  EXPECT_EQ(job->spp, 16);
  EXPECT_EQ(job->time_budget_s, 3.0);
}

TEST(JobFlagsTest, MalformedBudgetsAreRefusedNamingTheFlag) {
  for (const char* bad : {"0", "-1", "abc", "nan"}) {
    auto job = job_from_args({job_file("bad", R"("spp": 16)"), "--time-budget", bad});
    ASSERT_FALSE(job.ok()) << bad;
    EXPECT_NE(job.status().message().find("--time-budget"), std::string::npos) << job.status().message();
  }
}

TEST(JobFlagsTest, ExrCompressionOverridesTheFileAndIsCheckedWithTheJob) {
  auto job = job_from_args({job_file("codec", R"("spp": 1, "outputs": {"exr_compression": "piz"})"),
                            "--exr-compression", "rle"});
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  EXPECT_EQ(job->outputs.exr_compression, "rle");
  auto bad = job_from_args({job_file("codec_bad", R"("spp": 1)"), "--exr-compression", "lzma"});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("outputs.exr_compression"), std::string::npos) << bad.status().message();
}

}  // namespace
}  // namespace gdvr::tools
