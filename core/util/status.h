// Errors are values: core returns Status / Expected<T> with a message naming the
// offending input (file, line, field). The server maps Code onto gRPC codes in
// one place; core never exits and never throws across its API.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace gdvr {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,     // malformed input: bad XML, bad field value, NaN transform
  kNotFound,            // a named file, id or job does not exist
  kFailedPrecondition,  // valid request, wrong state (e.g. job already finished)
  kResourceExhausted,   // over a configured limit (resolution, spp, memory)
  kUnimplemented,       // a plugin or feature gdvr does not support
  kCancelled,           // stopped by a cancel flag
  kInternal,            // a library failed (Embree, OpenEXR, FFmpeg)
  kUnavailable,         // transient: try again
};

const char* status_code_name(StatusCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return Status(); }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  std::string to_string() const;
  // Prefix context ("scene.xml:12: ") while an error travels up.
  Status with_context(const std::string& prefix) const {
    return ok() ? *this : Status(code_, prefix + message_);
  }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

inline Status invalid_argument(std::string msg) { return {StatusCode::kInvalidArgument, std::move(msg)}; }
inline Status not_found(std::string msg) { return {StatusCode::kNotFound, std::move(msg)}; }
inline Status unimplemented(std::string msg) { return {StatusCode::kUnimplemented, std::move(msg)}; }
inline Status resource_exhausted(std::string msg) { return {StatusCode::kResourceExhausted, std::move(msg)}; }
inline Status internal_error(std::string msg) { return {StatusCode::kInternal, std::move(msg)}; }
inline Status cancelled(std::string msg) { return {StatusCode::kCancelled, std::move(msg)}; }
inline Status failed_precondition(std::string msg) { return {StatusCode::kFailedPrecondition, std::move(msg)}; }

// A value or the error that prevented it.
template <typename T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : v_(std::move(value)) {}         // NOLINT: implicit by design
  Expected(Status error) : v_(std::move(error)) {}    // NOLINT: must not be ok()
  bool ok() const { return std::holds_alternative<T>(v_); }
  const Status& status() const {
    static const Status kOk;
    return ok() ? kOk : std::get<Status>(v_);
  }
  T& value() & { return std::get<T>(v_); }
  const T& value() const& { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() { return value(); }

 private:
  std::variant<T, Status> v_;
};

#define GDVR_RETURN_IF_ERROR(expr)       \
  do {                                   \
    ::gdvr::Status _st = (expr);         \
    if (!_st.ok()) return _st;           \
  } while (0)

}  // namespace gdvr
