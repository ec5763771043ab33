#include "core/util/echo_text.h"

#include <cstdio>

namespace gdvr {
namespace {

bool is_continuation(unsigned char c) { return (c & 0xC0) == 0x80; }

void append_escaped(unsigned char c, std::string* out) {
  switch (c) {
    case '\n': *out += "\\n"; return;
    case '\t': *out += "\\t"; return;
    case '\r': *out += "\\r"; return;
    default: break;
  }
  if (c < 0x20 || c == 0x7f) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "\\x%02x", c);
    *out += buf;
    return;
  }
  *out += char(c);
}

size_t count_chars(std::string_view text) {
  size_t n = 0;
  for (unsigned char c : text) n += !is_continuation(c);
  return n;
}

}  // namespace

std::string escape_control_chars(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (unsigned char c : text) append_escaped(c, &out);
  return out;
}

std::string echo_text(std::string_view text, size_t max_chars) {
  const size_t total = count_chars(text);
  if (total <= max_chars) return escape_control_chars(text);
  // Cut before the (max_chars + 1)-th code point.
  size_t end = 0, chars = 0;
  while (end < text.size()) {
    if (!is_continuation(static_cast<unsigned char>(text[end]))) {
      if (chars == max_chars) break;
      ++chars;
    }
    ++end;
  }
  return escape_control_chars(text.substr(0, end)) + "\xE2\x80\xA6 (" + std::to_string(total) + " characters)";
}

}  // namespace gdvr
