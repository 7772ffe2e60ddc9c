#include "core/decimal.h"

namespace csgvox {

std::string toDecimal(double value) {
  std::string s;
  appendDecimal(s, value);
  return s;
}

}  // namespace csgvox
