// Command-line argument parsing shared by the core tools (gdvr-render,
// gdvr-report, gdvr-farm).
#pragma once

#include <string>

namespace gdvr::tools {

// Whole string `s` as an integer in [lo, hi]; false on anything else
// (trailing characters, overflow, out of range).
inline bool parse_int(const std::string& s, long long lo, long long hi, long long* out) {
  try {
    size_t pos;
    long long v = std::stoll(s, &pos);
    if (pos != s.size() || v < lo || v > hi) return false;
    *out = v;
    return true;
  } catch (...) {
    return false;
  }
}

}  // namespace gdvr::tools
