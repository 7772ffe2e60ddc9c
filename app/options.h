#pragma once
/// Checks of numeric command-line options, so that every bad value is a
/// usage error (exit 2) naming the option: CLI11's own Range lets NaN through
/// (every comparison with NaN is false) and reads "-5" as 2^64 - 5 for an
/// unsigned option.

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

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
