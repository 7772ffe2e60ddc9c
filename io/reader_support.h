#pragma once
/// Helpers shared by the file readers of io/: error messages that name the
/// source, stream sizes, word splitting and strict number parsing.

#include <cstdint>
#include <iosfwd>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace csgvox::detail {

/// Throws ParseError "<source>: <problem>".
/// @throw ParseError always.
[[noreturn]] void parseError(const std::string& source, const std::string& problem);

/// Number of bytes between the current position and the end of the stream.
/// @throw IoError when the stream is not seekable.
std::uint64_t bytesLeft(std::istream& in, const std::string& source);

/// Clears the stream's state and moves it back to its first byte.
void rewindStream(std::istream& in);

/// The whole (remaining) content of a stream.
/// @throw IoError when it cannot be read.
std::string slurp(std::istream& in, const std::string& source);

/// Replaces carriage returns, tabs and other blanks by spaces: CGAL's XYZ
/// and OBJ readers only treat ' ' as a separator (a "\r" line is an error,
/// and a tab ends an OBJ face after its first index).
void normalizeBlanks(std::string& text);

/// Silences std::cerr while a CGAL reader runs (some print diagnostics
/// unconditionally) and keeps what they printed for our message. Not safe
/// against other threads writing to std::cerr at the same time.
class CerrCapture {
 public:
  CerrCapture();
  ~CerrCapture();
  CerrCapture(const CerrCapture&) = delete;
  CerrCapture& operator=(const CerrCapture&) = delete;
  /// The first line CGAL printed.
  std::string firstLine() const;

 private:
  std::ostringstream buffer_;
  std::streambuf* previous_;
};

/// Throws the ParseError of a CGAL reader that sized a container from a
/// garbled count.
/// @throw ParseError always.
[[noreturn]] void garbledSize(const std::string& source);

/// Runs a CGAL reader, turning an allocation failure (a garbled count that
/// CGAL sizes a container with) into a ParseError.
/// @throw ParseError when the reader runs out of memory.
template <class Read>
bool guarded(const std::string& source, Read&& read) {
  try {
    return read();
  } catch (const std::bad_alloc&) {
  } catch (const std::length_error&) {
  }
  garbledSize(source);
}

/// The number after "line " in a CGAL diagnostic, or 0.
std::size_t lineNumberIn(const std::string& message);

/// The blank-separated words of a line (views into it).
std::vector<std::string_view> splitWords(std::string_view line);

/// Parses a whole word as an unsigned decimal count.
bool parseCount(std::string_view word, std::uint64_t& value);

/// Parses a whole word as a finite number (a leading '+' allowed).
bool parseFinite(std::string_view word, double& value);

/// sum + a * b, saturating at the largest uint64.
std::uint64_t saturatingMulAdd(std::uint64_t sum, std::uint64_t a, std::uint64_t b);

}  // namespace csgvox::detail
