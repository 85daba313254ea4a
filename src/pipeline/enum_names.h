// Internal: option words <-> enum values, one table per enum, so that the library, the CLI and
// the Python module accept the same words and say the same thing about unknown ones.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

template <class Enum>
using NameTable = std::vector<std::pair<const char*, Enum>>;

/// The value named `name`; throws Error "unknown WHAT 'NAME' (known: a, b, c)".
template <class Enum>
Enum parse_name(const NameTable<Enum>& table, const std::string& what, const std::string& name) {
  std::string known;
  for (const auto& [word, value] : table) {
    if (name == word) return value;
    known += (known.empty() ? "" : ", ") + std::string(word);
  }
  throw Error("unknown " + what + " '" + name + "' (known: " + known + ")");
}

/// The word for `value` ("?" if the table lacks it).
template <class Enum>
std::string name_of(const NameTable<Enum>& table, Enum value) {
  for (const auto& [word, v] : table)
    if (v == value) return word;
  return "?";
}

}  // namespace sdfcontour::detail
