// Tests for primitives/geometry.h: axis-aligned boxes and frames from an axis.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/geometry.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::Rng;

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(Aabb, DefaultIsEmpty) {
  const Aabb b;
  EXPECT_TRUE(b.isEmpty());
  EXPECT_FALSE(b.isBounded());
  EXPECT_EQ(b.diagonal(), 0.0);
  EXPECT_FALSE(b.contains(Vec3::Zero()));
}

TEST(Aabb, Everything) {
  const Aabb b = Aabb::everything();
  EXPECT_FALSE(b.isEmpty());
  EXPECT_FALSE(b.isBounded());
  EXPECT_EQ(b.diagonal(), kInf);
  EXPECT_TRUE(b.contains(Vec3(1e300, -1e300, 0)));
}

TEST(Aabb, ExtendIntersectAndMeasure) {
  Aabb b;
  b.extend(Vec3(1, 2, 3));
  EXPECT_FALSE(b.isEmpty());
  EXPECT_TRUE(b.isBounded());
  EXPECT_EQ(b.diagonal(), 0.0);
  b.extend(Vec3(-1, 4, 0));
  test::expectNear(b.min, Vec3(-1, 2, 0), 0.0);
  test::expectNear(b.max, Vec3(1, 4, 3), 0.0);
  test::expectNear(b.center(), Vec3(0, 3, 1.5), 0.0);
  test::expectNear(b.size(), Vec3(2, 2, 3), 0.0);
  EXPECT_DOUBLE_EQ(b.diagonal(), std::sqrt(17.0));
  EXPECT_TRUE(b.contains(Vec3(1, 2, 0)));  // closed box
  EXPECT_FALSE(b.contains(Vec3(1.001, 3, 1)));

  Aabb c{Vec3(0, 3, -5), Vec3(5, 5, 1)};
  const Aabb i = b.intersected(c);
  test::expectNear(i.min, Vec3(0, 3, 0), 0.0);
  test::expectNear(i.max, Vec3(1, 4, 1), 0.0);
  EXPECT_TRUE(b.intersected(Aabb{Vec3(2, 0, 0), Vec3(3, 1, 1)}).isEmpty());
  EXPECT_TRUE(b.intersected(Aabb()).isEmpty());
  const Aabb same = b.intersected(Aabb::everything());
  test::expectNear(same.min, b.min, 0.0);
  test::expectNear(same.max, b.max, 0.0);

  Aabb u = b;
  u.extend(Aabb());  // extending by an empty box changes nothing
  test::expectNear(u.min, b.min, 0.0);
  test::expectNear(u.max, b.max, 0.0);
  u.extend(c);
  test::expectNear(u.min, Vec3(-1, 2, -5), 0.0);
  test::expectNear(u.max, Vec3(5, 5, 3), 0.0);
  u.extend(Aabb::everything());
  EXPECT_FALSE(u.isBounded());
}

TEST(FrameFromAxis, IsRightHandedOrthonormalWithTheAxisThird) {
  Rng rng(1);
  std::vector<Vec3> axes = {Vec3::UnitX(),
                            Vec3::UnitY(),
                            Vec3::UnitZ(),
                            -Vec3::UnitZ(),
                            Vec3(1, 1, 1).normalized(),
                            Vec3(0, 1e-9, 1).normalized()};
  for (int i = 0; i < 100; ++i) axes.push_back(test::randomUnit(rng));
  for (const Vec3& a : axes) {
    const Mat3 f = frameFromAxis(a);
    EXPECT_TRUE(test::vecNear(f.col(2), a, 1e-15)) << test::str(a);
    EXPECT_LT((f.transpose() * f - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-14) << test::str(a);
    EXPECT_NEAR(f.determinant(), 1.0, 1e-14) << test::str(a);
    EXPECT_TRUE(f == frameFromAxis(a)) << "not deterministic";
  }
  EXPECT_TRUE(frameFromAxis(Vec3::UnitZ()).isApprox(Mat3::Identity(), 0.0));
  // A non-unit axis gives the frame of its direction.
  EXPECT_TRUE(frameFromAxis(Vec3(0, 3, 4)).isApprox(frameFromAxis(Vec3(0, 0.6, 0.8)), 1e-15));
}

}  // namespace
}  // namespace csgvox
