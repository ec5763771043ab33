// The spellings of an enum's values in job files, flags and logs, written once
// per enum as a table next to the enum. Names, parsing and the "one of ..."
// list in error messages all come from that table, so a value added to the
// enum and its table is accepted, printed and listed everywhere at once.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "core/util/echo_text.h"
#include "core/util/status.h"

namespace gdvr {

template <typename Enum>
struct NamedValue {
  Enum value;
  const char* name;
};

template <typename Enum, size_t N>
using EnumNames = std::array<NamedValue<Enum>, N>;

// The name of `value`, or "?" for a value the table lacks (a cast integer).
template <typename Enum, size_t N>
constexpr const char* enum_name(const EnumNames<Enum, N>& names, Enum value) {
  for (const NamedValue<Enum>& n : names)
    if (n.value == value) return n.name;
  return "?";
}

template <typename Enum, size_t N>
std::optional<Enum> enum_from_name(const EnumNames<Enum, N>& names, std::string_view name) {
  for (const NamedValue<Enum>& n : names)
    if (name == n.name) return n.value;
  return std::nullopt;
}

// "a, b or c", in table order: what error messages offer instead of a bad name.
template <typename Enum, size_t N>
std::string enum_name_list(const EnumNames<Enum, N>& names) {
  std::string out;
  for (size_t i = 0; i < N; ++i) {
    if (i > 0) out += i + 1 < N ? ", " : " or ";
    out += names[i].name;
  }
  return out;
}

// `name` as a value of the table, or INVALID_ARGUMENT "<what>: unknown
// '<name>' (expected a, b or c)"; the name is echoed bounded (it may come
// from a client).
template <typename Enum, size_t N>
Expected<Enum> parse_enum_name(const EnumNames<Enum, N>& names, const std::string& name, const char* what) {
  if (std::optional<Enum> v = enum_from_name(names, name)) return *v;
  return invalid_argument(std::string(what) + ": unknown '" + echo_text(name) + "' (expected " +
                          enum_name_list(names) + ")");
}

}  // namespace gdvr
