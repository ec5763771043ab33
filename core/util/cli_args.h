// Command-line argument parsing shared by the core tools (gdvr-render,
// gdvr-report, gdvr-farm and the gdvr-bench* benchmarks). A malformed value
// gets a message that names the option and what it expects, never an
// uncaught exception or a silent 0 (as std::stoi and std::atoi would give).
#pragma once

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

namespace gdvr::tools {

// Set by SIGINT/SIGTERM once install_interrupt_handlers() has run. The tools
// pass it as their job's cancel flag, so Ctrl-C or a farm's pre-emption stops
// the work within one tile and keeps every finished frame.
inline std::atomic<bool>& interrupted() {
  static std::atomic<bool> flag{false};
  return flag;
}
inline void install_interrupt_handlers() {
  interrupted();  // initialised here, not first inside the handler
  auto on_signal = [](int) { interrupted() = true; };
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

// "<tool>: <msg>" (when there is one) and the usage text on stderr; returns
// the usage exit code, 2.
inline int print_usage(const char* tool, const char* msg, const char* usage_text) {
  if (msg) std::fprintf(stderr, "%s: %s\n", tool, msg);
  std::fputs(usage_text, stderr);
  return 2;
}

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

// Whole string `s` as a finite number in [lo, hi]; false on anything else.
inline bool parse_number(const std::string& s, double lo, double hi, double* out) {
  try {
    size_t pos;
    double v = std::stod(s, &pos);
    if (pos != s.size() || !std::isfinite(v) || v < lo || v > hi) return false;
    *out = v;
    return true;
  } catch (...) {
    return false;
  }
}

// `--param NAME=VALUE`: sets params[NAME]; false without a name or '='.
inline bool parse_param(const std::string& kv, std::map<std::string, std::string>* params) {
  const size_t eq = kv.find('=');
  if (eq == std::string::npos || eq == 0) return false;
  (*params)[kv.substr(0, eq)] = kv.substr(eq + 1);
  return true;
}

// For the benchmark tools, whose options are all "--name VALUE": the value of
// option `name` as an integer in [lo, hi] (or a finite number), or a message
// "TOOL: NAME: expected ..." and exit status 2.
inline long long int_option(const char* tool, const std::string& name, const std::string& text, long long lo,
                            long long hi) {
  long long v = 0;
  if (parse_int(text, lo, hi, &v)) return v;
  std::fprintf(stderr, "%s: %s: expected an integer in [%lld, %lld], got '%s'\n", tool, name.c_str(), lo, hi,
               text.c_str());
  std::exit(2);
}

inline double number_option(const char* tool, const std::string& name, const std::string& text, double lo,
                            double hi) {
  double v = 0;
  if (parse_number(text, lo, hi, &v)) return v;
  std::fprintf(stderr, "%s: %s: expected a number in [%g, %g], got '%s'\n", tool, name.c_str(), lo, hi,
               text.c_str());
  std::exit(2);
}

}  // namespace gdvr::tools
