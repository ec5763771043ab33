#include "server/log.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>

#include "core/util/echo_text.h"

namespace gdvr::server {
namespace {

// A value is cut and its control characters escaped first: values echo
// client input (a 1.9 MB scene name once made a 1.9 MB log line, and a NUL
// byte went to the log raw).
constexpr size_t kMaxLogValueChars = 2000;

std::string quote_if_needed(const std::string& raw) {
  const std::string v = echo_text(raw, kMaxLogValueChars);
  bool plain = !v.empty();
  for (char c : v)
    if (c == ' ' || c == '"' || c == '=' || c == '\n' || c == '\t') plain = false;
  if (plain) return v;
  std::string out = "\"";
  for (char c : v) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') { out += "\\n"; continue; }
    out += c;
  }
  return out + "\"";
}

}  // namespace

void log_event(const char* level, const char* event, std::initializer_list<LogField> fields) {
  using namespace std::chrono;
  auto now = system_clock::now();
  std::time_t t = system_clock::to_time_t(now);
  int ms = int(duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char ts[64];
  std::snprintf(ts, sizeof ts, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1,
                tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, ms);
  std::string line = std::string("ts=") + ts + " level=" + level + " event=" + event;
  for (const auto& [k, v] : fields) line += std::string(" ") + k + "=" + quote_if_needed(v);
  line += '\n';
  static std::mutex mu;
  std::lock_guard<std::mutex> lock(mu);
  std::fwrite(line.data(), 1, line.size(), stderr);
  std::fflush(stderr);
}

}  // namespace gdvr::server
