// Test helper: a job's stage-1 buffers for the given frames (render_job_buffers
// on two threads), by frame number.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "core/job/job_runner.h"

namespace gdvr::test {

inline std::map<int, FrameBuffers> render_buffers(const JobSpec& job, const std::string& base_dir,
                                                  const std::vector<int>& frames) {
  JobRunOptions options;
  options.base_dir = base_dir;
  options.threads = 2;
  std::map<int, FrameBuffers> out;
  Status st = render_job_buffers(job, options, frames, [&](FrameBuffers&& b) {
    out[b.frame] = std::move(b);
    return Status::Ok();
  }, nullptr, nullptr);
  EXPECT_TRUE(st.ok()) << st.to_string();
  return out;
}

}  // namespace gdvr::test
