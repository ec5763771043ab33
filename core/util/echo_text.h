// Text that came from a user or a client (a scene name, a frame range, a
// JSON key), quoted back in an error message or a log line. Such input can be
// megabytes long or hold NUL and control bytes; quoted raw, it makes a gRPC
// status too big for the client's 16 KiB metadata limit (the client then sees
// "Stream removed" instead of the error) and breaks one-line logs. Every echo
// of outside input goes through echo_text.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace gdvr {

// How much of an echoed input is kept: enough to recognise it.
constexpr size_t kEchoMaxChars = 200;

// `text` with control characters and NUL escaped (\n, \t, \r, \xNN) and, when
// longer than `max_chars` characters (UTF-8 code points), cut there with the
// marker "… (N characters)" giving the full length. Never splits a UTF-8
// sequence.
std::string echo_text(std::string_view text, size_t max_chars = kEchoMaxChars);

// Only the escaping of echo_text (no cut), for text that is bounded already.
std::string escape_control_chars(std::string_view text);

}  // namespace gdvr
