#include "core/named_values.h"

#include <charconv>

namespace csgvox {
namespace {

std::string shortest(double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof(buf), v);
  return ec == std::errc() ? std::string(buf, end) : std::to_string(v);
}

}  // namespace

std::string OptionRange::text() const { return "[" + shortest(lo) + ", " + shortest(hi) + "]"; }

void checkRange(std::string_view name, double value, const OptionRange& range) {
  if (!range.contains(value)) {
    throw std::invalid_argument(std::string(name) + " must be in " + range.text());
  }
}

}  // namespace csgvox
