// One table of names per enum, read both ways: the Parse…(name, field) a codec or a flag
// parser calls at the edge, and the …Name(value) that prints it. A name outside the table
// is INVALID_ARGUMENT naming the field and listing every accepted name, in table order:
//     "<field> '<name>' is not one of: <a>, <b>, <c>"
// The engine itself takes the enum and never parses.
#pragma once

#include <cstddef>
#include <string>

#include "engine/core/status.h"

namespace localizer::engine {

template <typename Enum>
struct EnumName {
  Enum value;
  const char* name;
};

template <typename Enum, size_t N>
StatusOr<Enum> ParseEnumName(const std::string& name, const std::string& field, const EnumName<Enum> (&table)[N]) {
  for (const EnumName<Enum>& entry : table) {
    if (name == entry.name) return entry.value;
  }
  std::string accepted;
  for (size_t i = 0; i < N; ++i) accepted += std::string(i == 0 ? "" : ", ") + table[i].name;
  return InvalidArgument(field + " '" + name + "' is not one of: " + accepted);
}

// The table's name for `value` ("?" for a value outside the table: a cast, never a parse).
template <typename Enum, size_t N>
const char* EnumNameOf(Enum value, const EnumName<Enum> (&table)[N]) {
  for (const EnumName<Enum>& entry : table) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

}  // namespace localizer::engine
