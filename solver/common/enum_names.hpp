#pragma once
/// \file enum_names.hpp
/// Named enum values: the options that JSON files and the command line give as strings (solver
/// names, collision rules, ...) are enums in the code. Each such enum has one table of {value,
/// name} pairs, and its ToString, <Enum>FromString and <Enum>Names are these helpers over it, so
/// that the names are listed once.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace softkin {

/// The names of an enum's values: {value, name} pairs, in the order the names are listed.
template <class E>
using EnumName = std::pair<E, const char*>;

/// The name of v in `table` ("?" if it is not there, which a valid enum value never is).
template <class E, std::size_t N>
std::string EnumToString(const EnumName<E> (&table)[N], E v) {
  for (const auto& [value, name] : table)
    if (value == v) return name;
  return "?";
}

/// Every name of `table`, in table order.
template <class E, std::size_t N>
std::vector<std::string> EnumNames(const EnumName<E> (&table)[N]) {
  std::vector<std::string> names;
  for (const auto& entry : table) names.push_back(entry.second);
  return names;
}

/// "a, b, c": names for messages and help texts.
inline std::string NameList(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

/// The value named s. Throws std::invalid_argument "unknown <what> 's'; expected one of: a, b"
/// for any other string.
template <class E, std::size_t N>
E EnumFromString(const EnumName<E> (&table)[N], const std::string& s, const std::string& what) {
  for (const auto& [value, name] : table)
    if (s == name) return value;
  throw std::invalid_argument("unknown " + what + " '" + s +
                              "'; expected one of: " + NameList(EnumNames(table)));
}

}  // namespace softkin
