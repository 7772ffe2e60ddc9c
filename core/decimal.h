#pragma once
/// Numbers as the shortest decimal text that reads back to the same value.

#include <charconv>
#include <concepts>
#include <string>

namespace csgvox {

/// Appends `value` to `out` as the shortest decimal text that reads back
/// (std::from_chars, strtod) to exactly `value`: "0.1", "1e+300", "-0",
/// "inf", "nan". Integers are written in full.
template <class T>
requires std::integral<T> || std::floating_point<T>
void appendDecimal(std::string& out, T value) {
  char text[64];
  const auto result = std::to_chars(text, text + sizeof text, value);
  out.append(text, result.ptr);
}

/// `value` as the shortest decimal text that reads back to exactly `value`.
std::string toDecimal(double value);

}  // namespace csgvox
