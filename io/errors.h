#pragma once
/// Exceptions for bad input and environment. The CLI maps them to a non-zero
/// exit code and one line on stderr; the message always names the file.

#include <stdexcept>
#include <string>

namespace csgvox {

/// A file cannot be opened, read or written (missing, a directory, no
/// permission, disk full).
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file was read but its content is not valid (wrong header, truncated,
/// NaN coordinates, too few points, bad tree).
class ParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace csgvox
