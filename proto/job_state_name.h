// A JobState as people read it ("queued", "running", "cancelling", ...): in
// the CLI, the server's log and stats.json. Derived from the enum's own names,
// so a state added to render_service.proto needs no change here.
#pragma once

#include <cctype>
#include <string>

#include "gdvr/v1/render_service.pb.h"

namespace gdvr {

inline std::string job_state_name(v1::JobState state) {
  std::string name = v1::JobState_Name(state);  // "JOB_STATE_QUEUED"; "" for a value this build does not know
  const std::string prefix = "JOB_STATE_";
  if (name.compare(0, prefix.size(), prefix) != 0) return "unknown";
  name.erase(0, prefix.size());
  for (char& c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

}  // namespace gdvr
