#include "io/reader_support.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <iostream>
#include <new>
#include <stdexcept>

#include "io/errors.h"

namespace csgvox::detail {

void parseError(const std::string& source, const std::string& problem) {
  throw ParseError(source + ": " + problem);
}

std::uint64_t bytesLeft(std::istream& in, const std::string& source) {
  if (in.eof() && !in.bad()) in.clear();  // at the end: nothing left
  const std::streampos pos = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streampos end = in.tellg();
  in.seekg(pos);
  if (pos < 0 || end < 0 || !in)
    throw IoError(source + ": cannot be read (stream is not seekable)");
  return static_cast<std::uint64_t>(end - pos);
}

void rewindStream(std::istream& in) {
  in.clear();
  in.seekg(0);
}

std::string slurp(std::istream& in, const std::string& source) {
  std::string text(bytesLeft(in, source), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (static_cast<std::size_t>(in.gcount()) != text.size()) throw IoError(source + ": read failed");
  return text;
}

void normalizeBlanks(std::string& text) {
  for (char& c : text) {
    if (c == '\r' || c == '\t' || c == '\v' || c == '\f') c = ' ';
  }
}

CerrCapture::CerrCapture() : previous_(std::cerr.rdbuf(buffer_.rdbuf())) {}

CerrCapture::~CerrCapture() { std::cerr.rdbuf(previous_); }

std::string CerrCapture::firstLine() const {
  const std::string text = buffer_.str();
  return text.substr(0, text.find('\n'));
}

void garbledSize(const std::string& source) {
  parseError(source, "garbled file (it states a size far larger than the file)");
}

std::size_t lineNumberIn(const std::string& message) {
  const std::size_t at = message.find("line ");
  std::size_t line = 0;
  if (at != std::string::npos) {
    const char* first = message.data() + at + 5;
    std::from_chars(first, message.data() + message.size(), line);
  }
  return line;
}

std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) words.emplace_back(line.substr(start, i - start));
  }
  return words;
}

bool parseCount(std::string_view word, std::uint64_t& value) {
  const char* end = word.data() + word.size();
  const auto result = std::from_chars(word.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

bool parseFinite(std::string_view word, double& value) {
  if (word.starts_with('+')) word.remove_prefix(1);
  const char* end = word.data() + word.size();
  const auto result = std::from_chars(word.data(), end, value);
  return result.ec == std::errc() && result.ptr == end && std::isfinite(value);
}

std::uint64_t saturatingMulAdd(std::uint64_t sum, std::uint64_t a, std::uint64_t b) {
  constexpr std::uint64_t kMax = ~std::uint64_t{0};
  if (a != 0 && b > kMax / a) return kMax;
  return sum > kMax - a * b ? kMax : sum + a * b;
}

}  // namespace csgvox::detail
