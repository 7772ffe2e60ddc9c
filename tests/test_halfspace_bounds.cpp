// Bounds of intersections of half-spaces (core/halfspace_bounds.h) and of
// trees made of them (CsgTree::bounds).

#include <gtest/gtest.h>

#include <cmath>

#include "core/csg_tree.h"
#include "core/halfspace_bounds.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

std::vector<HalfSpace> block(const Vec3& lo, const Vec3& hi) {
  std::vector<HalfSpace> out;
  for (int k = 0; k < 3; ++k) {
    out.push_back({Vec3::Unit(k), hi[k]});
    out.push_back({-Vec3::Unit(k), -lo[k]});
  }
  return out;
}

TEST(HalfSpaceBounds, SixFacesBoundABlock) {
  const Aabb b =
      halfSpaceIntersectionBounds(block(Vec3(-1, -2, -3), Vec3(4, 5, 6)), Aabb::everything());
  EXPECT_TRUE(test::vecNear(b.min, Vec3(-1, -2, -3), 1e-6));
  EXPECT_TRUE(test::vecNear(b.max, Vec3(4, 5, 6), 1e-6));
}

TEST(HalfSpaceBounds, AnOpenDirectionStaysInfinite) {
  std::vector<HalfSpace> five = block(Vec3(-1, -1, -1), Vec3(1, 1, 1));
  five.erase(five.begin() + 4);  // no top face (z <= 1)
  const Aabb b = halfSpaceIntersectionBounds(five, Aabb::everything());
  EXPECT_TRUE(std::isinf(b.max.z()));
  EXPECT_NEAR(b.min.z(), -1.0, 1e-6);
  EXPECT_NEAR(b.max.x(), 1.0, 1e-6);
  // A finite box closes it.
  Aabb box;
  box.extend(Vec3(-5, -5, -5));
  box.extend(Vec3(5, 5, 3));
  EXPECT_NEAR(halfSpaceIntersectionBounds(five, box).max.z(), 3.0, 1e-6);
}

TEST(HalfSpaceBounds, ATiltedSlabAndAnEmptyIntersection) {
  // The tetrahedron x, y, z >= 0, x + y + z <= 1.
  std::vector<HalfSpace> tet = {{-Vec3::UnitX(), 0},
                                {-Vec3::UnitY(), 0},
                                {-Vec3::UnitZ(), 0},
                                {Vec3(1, 1, 1).normalized(), 1 / std::sqrt(3.0)}};
  const Aabb b = halfSpaceIntersectionBounds(tet, Aabb::everything());
  EXPECT_TRUE(test::vecNear(b.min, Vec3::Zero(), 1e-6));
  EXPECT_TRUE(test::vecNear(b.max, Vec3::Ones(), 1e-6));
  tet.push_back({Vec3(-1, -1, -1).normalized(), -2 / std::sqrt(3.0)});  // x + y + z >= 2
  EXPECT_TRUE(halfSpaceIntersectionBounds(tet, Aabb::everything()).isEmpty());
}

TEST(HalfSpaceBounds, TreesOfHalfSpacesHaveFiniteBounds) {
  std::vector<CsgTree> faces;
  for (const HalfSpace& h : block(Vec3(-1, -1, -1), Vec3(1, 1, 1)))
    faces.push_back(CsgTree::leaf(h));
  // A binary chain, as the genetic search builds it, with a subtracted and a
  // complemented half-space among the operands.
  const CsgTree chain =
      CsgTree::intersect({CsgTree::intersect({faces[0], faces[1]}),
                          CsgTree::subtract({CsgTree::intersect({faces[2], faces[3], faces[4]}),
                                             CsgTree::leaf(HalfSpace{Vec3::UnitZ(), -1.0})}),
                          CsgTree::complement(CsgTree::leaf(HalfSpace{Vec3::UnitX(), -0.5}))});
  const Aabb b = chain.bounds();
  ASSERT_TRUE(b.isBounded());
  EXPECT_TRUE(test::vecNear(b.min, Vec3(-0.5, -1, -1), 1e-6));
  EXPECT_TRUE(test::vecNear(b.max, Vec3(1, 1, 1), 1e-6));
  // Union with a half-space is unbounded.
  EXPECT_FALSE(CsgTree::unite({chain, faces[0]}).bounds().isBounded());
}

}  // namespace
}  // namespace csgvox
