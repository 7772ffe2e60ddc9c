#pragma once
/// Name <-> enum tables: the one place where an option's accepted names are
/// listed, read by the command line, the Python module and the reports.

#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

namespace csgvox {

/// One accepted name of an enum value.
template <class E>
struct NamedValue {
  std::string_view name;  ///< the word users type and reports print
  E value;
};

/// "a, b or c": the names of a table, for messages and help texts.
template <class E>
std::string namesText(std::type_identity_t<std::span<const NamedValue<E>>> table) {
  std::string text;
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (i > 0) text += i + 1 == table.size() ? " or " : ", ";
    text += table[i].name;
  }
  return text;
}

/// The name of `value` in `table` (the first that names it).
/// @throw std::logic_error when the table lacks the value (a table out of date).
template <class E>
std::string_view nameOf(std::type_identity_t<std::span<const NamedValue<E>>> table, E value) {
  for (const NamedValue<E>& entry : table) {
    if (entry.value == value) return entry.name;
  }
  throw std::logic_error("a value missing from its name table");
}

/// The value named `name` in `table`; `what` names the option in the error.
/// @throw std::invalid_argument "unknown <what> '<name>' (a, b or c)" for another name.
template <class E>
E valueNamed(std::span<const NamedValue<E>> table, std::string_view name, std::string_view what) {
  for (const NamedValue<E>& entry : table) {
    if (entry.name == name) return entry.value;
  }
  throw std::invalid_argument("unknown " + std::string(what) + " '" + std::string(name) + "' (" +
                              namesText<E>(table) + ")");
}

/// The accepted closed range of a numeric option.
struct OptionRange {
  double lo = 0.0;
  double hi = 0.0;
  /// A finite number in [lo, hi].
  bool contains(double v) const { return v >= lo && v <= hi; }
  /// "[lo, hi]", numbers as the shortest text that reads back exactly.
  std::string text() const;
};

/// Checks a numeric option against its range.
/// @throw std::invalid_argument "<name> must be in [lo, hi]" when it is not (NaN included).
void checkRange(std::string_view name, double value, const OptionRange& range);

}  // namespace csgvox
