// The one check of a job's values, whoever built it: parse_job_json runs it
// on every job file and RPC (the server's JobSpec arrives as its JSON form),
// gdvr-render again after its flags changed the job, and the job runner before
// it loads the scene. Errors name the field as the job file spells it
// ("job.reconstruction.window: must be in [1, 1000]").
#pragma once

#include "core/job/job_spec.h"
#include "core/util/status.h"

namespace gdvr {

// Field ranges and the frame range syntax; touches no file (the scene and the
// outputs are checked where they are opened: validate_job, JobOutputs).
// A frame range over the frame limit is RESOURCE_EXHAUSTED, every other
// problem INVALID_ARGUMENT.
Status validate(const JobSpec& job);

}  // namespace gdvr
