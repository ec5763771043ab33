// Structured logs: one line per event on stderr, `key=value` pairs, values
// quoted when they contain spaces, so that `grep job=...` follows a job.
// Values are bounded and their control characters escaped (log.cpp): one
// event is always one line of reasonable length.
#pragma once

#include <initializer_list>
#include <string>
#include <utility>

namespace gdvr::server {

using LogField = std::pair<const char*, std::string>;

// level: "info" | "warn" | "error". Thread-safe; lines never interleave.
void log_event(const char* level, const char* event, std::initializer_list<LogField> fields = {});

}  // namespace gdvr::server
