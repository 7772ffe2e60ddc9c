// Tests for core/decimal.h.

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <string>

#include "core/decimal.h"

namespace csgvox {
namespace {

TEST(Decimal, ShortestTextThatReadsBack) {
  EXPECT_EQ(toDecimal(0.1), "0.1");
  EXPECT_EQ(toDecimal(2.5), "2.5");
  EXPECT_EQ(toDecimal(-0.0), "-0");
  EXPECT_EQ(toDecimal(1e300), "1e+300");
  EXPECT_EQ(toDecimal(std::numeric_limits<double>::infinity()), "inf");
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> exponent(-300.0, 300.0);
  for (int i = 0; i < 10000; ++i) {
    const double x = std::pow(10.0, exponent(rng)) * (i % 2 ? 1.0 : -1.0);
    const std::string text = toDecimal(x);
    EXPECT_EQ(std::stod(text), x) << text;
    EXPECT_LE(text.size(), 24u);
  }
}

TEST(Decimal, AppendsFloatsAndIntegers) {
  std::string s = "x=";
  appendDecimal(s, 0.1f);  // the float's own shortest form, not the double's
  s += ' ';
  appendDecimal(s, std::uint8_t{255});
  s += ' ';
  appendDecimal(s, -42);
  EXPECT_EQ(s, "x=0.1 255 -42");
}

}  // namespace
}  // namespace csgvox
