// Tests for core/statistics.h.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/statistics.h"

namespace csgvox {
namespace {

TEST(Median, OddEvenAndEmpty) {
  EXPECT_EQ(median({5.0}), 5.0);
  EXPECT_EQ(median({3.0, -1.0, 2.0}), 2.0);
  // An even count gives the upper of the two middle values (one of the samples).
  EXPECT_EQ(median({4.0, 1.0, 3.0, 2.0}), 3.0);
  EXPECT_EQ(median({1.0, 1.0, 7.0, 7.0}), 7.0);
  EXPECT_TRUE(std::isnan(median({})));
}

TEST(Median, IgnoresOutliers) {
  std::vector<double> v(101, 1.0);
  for (int i = 0; i < 50; ++i) v[std::size_t(i)] = 1e300;
  EXPECT_EQ(median(v), 1.0);
}

}  // namespace
}  // namespace csgvox
