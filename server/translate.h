// Translation between gdvr.v1 messages and core types.
//
// A v1::JobSpec becomes a core JobSpec through its protobuf JSON form, on
// purpose: that form is the job file (proto/gdvr/v1/job.proto mirrors
// core/job/job_spec.h field for field), so core's parse_job_json is the one
// reader of both, and a client gets the same error, naming the same field,
// whether it sent a job file or a message. A field-by-field translation here
// would be a second reader of the schema to keep in step with the first: the
// keyframe forms (`frame` converted with the job's fps, lookat,
// translate/rotate/scale, tracks at the top level or under `animation`), the
// names of integrators, shifts and methods, and the unset scalars (proto3
// `optional` presence is JSON presence, so both fall back to the same
// defaults). The round trip costs microseconds per submitted job.
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
