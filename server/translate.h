// Translation between gdvr.v1 messages and core types. JobSpec crosses through
// its JSON form (the job file), so core's parse_job_json stays the one parser
// and validator of job fields.
#pragma once

#include <string>

#include "core/job/job_runner.h"
#include "core/job/job_spec.h"
#include "gdvr/v1/render_service.pb.h"

namespace gdvr::server {

// The job file text for a spec: proto field names, 64-bit integers as JSON
// numbers (protobuf prints them as strings; the job file uses numbers).
std::string job_spec_to_json(const v1::JobSpec& spec);
// Parses a job file; unknown or mistyped fields are INVALID_ARGUMENT naming them.
Expected<v1::JobSpec> job_spec_from_json(const std::string& json_text, const std::string& origin);
Expected<JobSpec> to_core_job(const v1::JobSpec& spec);

void to_proto(const FrameStats& stats, v1::FrameStats* out);
FrameStats from_proto(const v1::FrameStats& stats);
void to_proto(const JobProgress& progress, v1::Progress* out);

}  // namespace gdvr::server
