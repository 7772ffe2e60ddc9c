#pragma once
/// Checks of numeric command-line options, so that every bad value is a
/// usage error (exit 2) naming the option: CLI11's own Range lets NaN through
/// (every comparison with NaN is false) and reads "-5" as 2^64 - 5 for an
/// unsigned option.

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/named_values.h"

namespace csgvox::app {

/// A finite number in [lo, hi].
inline CLI::Validator inRange(double lo, double hi) {
  const std::string range =
      "[" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        errno = 0;
        const double v = std::strtod(begin, &end);
        if (end == begin || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(v) || errno == ERANGE) return "'" + text + "' is not a finite number";
        if (v < lo || v > hi) return text + " is not in " + range;
        return {};
      },
      "in " + range);
}

/// A finite number in the option's range.
inline CLI::Validator inRange(const OptionRange& range) { return inRange(range.lo, range.hi); }

/// An option whose value is one of the names of `table`, stored as the enum
/// value it names; --help lists the names and shows the current value's
/// name as the default. The text given stays as typed (batch passes it on).
template <class E>
CLI::Option* addNamedOption(CLI::App& app, const std::string& flags, E& target,
                            std::type_identity_t<std::span<const NamedValue<E>>> table,
                            const std::string& help) {
  std::vector<std::string> names;
  for (const NamedValue<E>& entry : table) names.emplace_back(entry.name);
  return app
      .add_option_function<std::string>(
          flags,
          [&target, table](const std::string& name) {
            target = valueNamed<E>(table, name, "value");
          },
          help)
      ->check(CLI::IsMember(names))
      ->default_str(std::string(nameOf<E>(table, target)));
}

/// A non-negative integer (for seeds and counts held unsigned).
inline CLI::Validator nonNegativeInteger() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) {
          return "'" + text + "' is not a non-negative integer";
        }
        return {};
      },
      "INT >= 0");
}

}  // namespace csgvox::app
