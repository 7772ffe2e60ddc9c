// Tests for core/principal_axes.h.

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "core/principal_axes.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::Rng;

TEST(PrincipalAxes, OfAStretchedRotatedCloud) {
  Rng rng(1);
  const Mat3 rotation = test::randomRotation(rng);
  const Vec3 sd(3.0, 1.0, 0.1), centre(5, -1, 2);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 20000; ++i) {
    points.push_back(centre +
                     rotation * Vec3(sd[0] * gauss(rng), sd[1] * gauss(rng), sd[2] * gauss(rng)));
  }
  const PrincipalAxes pa = principalAxes(points);
  test::expectNear(pa.mean, centre, 0.1);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(std::sqrt(pa.variances[k]), sd[k], 0.05 * sd[k]) << k;
    EXPECT_GT(std::abs(pa.axes.col(k).dot(rotation.col(k))), 0.99) << k;
  }
  EXPECT_TRUE((pa.axes.transpose() * pa.axes).isApprox(Mat3::Identity(), 1e-12));
  test::expectNear(pa.leastAxis(), pa.axes.col(2), 0.0);
  EXPECT_NEAR(pa.covariance.trace(), pa.variances.sum(), 1e-9);
}

TEST(PrincipalAxes, ExactValuesAndIndexedSubsets) {
  // Four points of a 2 x 4 rectangle in the plane z = 7: variances 4 and 1
  // (the covariance is divided by n), none across.
  const std::vector<Vec3> points{Vec3(0, 0, 7), Vec3(4, 0, 7), Vec3(0, 2, 7), Vec3(4, 2, 7),
                                 Vec3(100, 100, 100)};
  const std::vector<std::uint32_t> rectangle{0, 1, 2, 3};
  const PrincipalAxes pa = principalAxes(points, rectangle);
  test::expectNear(pa.mean, Vec3(2, 1, 7), 1e-15);
  test::expectNear(pa.variances, Vec3(4, 1, 0), 1e-12);
  EXPECT_GT(std::abs(pa.axes.col(0).x()), 1.0 - 1e-12);
  EXPECT_GT(std::abs(pa.leastAxis().z()), 1.0 - 1e-12);
  const std::vector<Vec3> copied(points.begin(), points.begin() + 4);
  const PrincipalAxes same = principalAxes(copied);
  EXPECT_EQ(same.covariance, pa.covariance);
  EXPECT_EQ(same.axes, pa.axes);
}

TEST(PrincipalAxes, EmptySetIsZero) {
  const PrincipalAxes pa = principalAxes(std::vector<Vec3>{});
  EXPECT_EQ(pa.mean, Vec3::Zero());
  EXPECT_EQ(pa.variances, Vec3::Zero());
  EXPECT_EQ(pa.axes, Mat3::Identity());
}

}  // namespace
}  // namespace csgvox
