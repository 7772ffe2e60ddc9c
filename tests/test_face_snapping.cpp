// snapFaces: near-coincident flat caps move onto the plane of the largest
// (a half-space's, a torus's equator), caps farther apart stay, nearly
// parallel directions become exactly parallel, a cone keeps its lateral
// surface, a thin primitive is not flattened, names and sharing are kept.

#include <gtest/gtest.h>

#include <stdexcept>

#include "cad/face_snapping.h"

namespace csgvox {
namespace {

const Node& child(const CsgTree& tree, std::size_t i) { return *tree.root()->children[i]; }

CsgTree plateAndBoss(double bossBottom) {
  const CsgTree plate =
      CsgTree::leaf(Box{Vec3(5, 5, 2.5), Mat3::Identity(), Vec3(5, 5, 2.5)}, "plate");
  const CsgTree boss = CsgTree::leaf(
      Cylinder{Vec3(5, 5, 0.5 * (bossBottom + 10.0)), Vec3::UnitZ(), 3.0, 10.0 - bossBottom},
      "boss");
  return CsgTree::unite({plate, boss});
}

TEST(FaceSnapping, TheSmallerCapMovesOntoTheLargerOnesPlane) {
  const FaceSnapResult r = snapFaces(plateAndBoss(5.01), {.tolerance = 0.02});
  EXPECT_EQ(r.movedCaps, 1u);
  EXPECT_NEAR(r.largestMove, 0.01, 1e-12);
  const Box& plate = *child(r.tree, 0).primitive.as<Box>();
  EXPECT_EQ(plate.center, Vec3(5, 5, 2.5));
  EXPECT_EQ(plate.halfSize, Vec3(5, 5, 2.5));
  const Cylinder& boss = *child(r.tree, 1).primitive.as<Cylinder>();
  EXPECT_NEAR(boss.center.z() - 0.5 * boss.height, 5.0, 1e-12);
  EXPECT_NEAR(boss.center.z() + 0.5 * boss.height, 10.0, 1e-12);
  EXPECT_EQ(child(r.tree, 0).name, "plate");
  EXPECT_EQ(child(r.tree, 1).name, "boss");
}

TEST(FaceSnapping, CapsFartherApartThanTheToleranceStay) {
  const CsgTree tree = plateAndBoss(5.05);
  const FaceSnapResult r = snapFaces(tree, {.tolerance = 0.02});
  EXPECT_EQ(r.movedCaps, 0u);
  EXPECT_TRUE(r.tree.structurallyEqual(tree));
}

TEST(FaceSnapping, AHalfSpacesPlaneStaysAndTheCapsComeToIt) {
  // A large box's top 0.01 above the plane z = 3: the box's face moves.
  const CsgTree box = CsgTree::leaf(Box{Vec3(0, 0, 1.505), Mat3::Identity(), Vec3(50, 50, 1.505)});
  const CsgTree cut = CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 3.0});
  const FaceSnapResult r = snapFaces(CsgTree::intersect({box, cut}), {.tolerance = 0.02});
  EXPECT_EQ(child(r.tree, 1).primitive.as<HalfSpace>()->offset, 3.0);
  const Box& b = *child(r.tree, 0).primitive.as<Box>();
  EXPECT_NEAR(b.center.z() + b.halfSize.z(), 3.0, 1e-12);
  EXPECT_NEAR(b.center.z() - b.halfSize.z(), 0.0, 1e-12);
}

TEST(FaceSnapping, ACapNearATorussEquatorMovesThere) {
  // A fillet ring: a cylinder ending 0.005 below the equator of the torus
  // that rounds it.
  const CsgTree ring = CsgTree::leaf(Cylinder{Vec3(0, 0, 16.9975), Vec3::UnitZ(), 38.0, 5.995});
  const CsgTree torus = CsgTree::leaf(Torus{Vec3(0, 0, 20), Vec3::UnitZ(), 38.0, 6.0});
  const FaceSnapResult r = snapFaces(CsgTree::subtract({ring, torus}), {.tolerance = 0.02});
  const Cylinder& c = *child(r.tree, 0).primitive.as<Cylinder>();
  EXPECT_NEAR(c.center.z() + 0.5 * c.height, 20.0, 1e-12);
  EXPECT_NEAR(c.center.z() - 0.5 * c.height, 14.0, 1e-12);  // not near a plane: kept
  const FaceSnapResult off =
      snapFaces(CsgTree::subtract({ring, torus}), {.tolerance = 0.02, .torusEquator = false});
  EXPECT_EQ(off.movedCaps, 0u);
}

TEST(FaceSnapping, NearlyParallelAxesBecomeExactlyParallel) {
  const Vec3 tilted = Vec3(1e-8, -2e-8, 1.0).normalized();
  const CsgTree a = CsgTree::leaf(Cylinder{Vec3(0, 0, 5), tilted, 2.0, 10.0});
  const CsgTree b = CsgTree::leaf(Box{Vec3(0, 0, 5), Mat3::Identity(), Vec3(1, 1, 5)});
  const CsgTree far = CsgTree::leaf(Cylinder{Vec3(0, 0, 5), Vec3(0, 0.01, 1).normalized(), 1, 3});
  const FaceSnapResult r = snapFaces(CsgTree::unite({a, b, far}), {.tolerance = 1e-9});
  EXPECT_EQ(r.turnedAxes, 1u);
  EXPECT_EQ(child(r.tree, 0).primitive.as<Cylinder>()->axis, Vec3::UnitZ());
  EXPECT_EQ(child(r.tree, 2).primitive.as<Cylinder>()->axis, Vec3(0, 0.01, 1).normalized());
}

TEST(FaceSnapping, AConeKeepsItsLateralSurface) {
  // A frustum from z = 0 (radius 2) to z = 4.99 (radius 1.002) under a
  // plate whose bottom is z = 5.
  const Cone cone{Vec3(0, 0, 2.495), Vec3::UnitZ(), 2.0, 2.0 - 0.2 * 4.99, 4.99};
  const CsgTree plate = CsgTree::leaf(Box{Vec3(0, 0, 6), Mat3::Identity(), Vec3(5, 5, 1)});
  const FaceSnapResult r =
      snapFaces(CsgTree::unite({CsgTree::leaf(cone), plate}), {.tolerance = 0.02});
  const Cone& c = *child(r.tree, 0).primitive.as<Cone>();
  EXPECT_NEAR(c.center.z() + 0.5 * c.height, 5.0, 1e-12);
  EXPECT_NEAR(c.center.z() - 0.5 * c.height, 0.0, 1e-12);
  EXPECT_NEAR(c.radiusBottom, 2.0, 1e-12);
  EXPECT_NEAR(c.radiusTop, 1.0, 1e-12);
}

TEST(FaceSnapping, APrimitiveThinnerThanTheToleranceIsNotFlattened) {
  const CsgTree sheet = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(5, 5, 0.005)});
  const CsgTree post = CsgTree::leaf(Cylinder{Vec3(0, 0, 2.5), Vec3::UnitZ(), 1.0, 5.0});
  const FaceSnapResult r = snapFaces(CsgTree::unite({sheet, post}), {.tolerance = 0.02});
  const Box& b = *child(r.tree, 0).primitive.as<Box>();
  EXPECT_NEAR(b.halfSize.z(), 0.005, 1e-12);
}

TEST(FaceSnapping, SharedSubtreesStayShared) {
  const CsgTree hole = CsgTree::leaf(Cylinder{Vec3(0, 0, 5), Vec3::UnitZ(), 1.0, 10.01}, "bore");
  const CsgTree a = CsgTree::leaf(Box{Vec3(0, 0, 5), Mat3::Identity(), Vec3(3, 3, 5)});
  const CsgTree tree(std::make_shared<const Node>(
      NodeKind::Union, std::vector<NodePtr>{CsgTree::subtract({a, hole}).root(),
                                            CsgTree::intersect({a, hole}).root()}));
  ASSERT_EQ(tree.root()->children[0]->children[1], tree.root()->children[1]->children[1]);
  const FaceSnapResult r = snapFaces(tree, {.tolerance = 0.02});
  EXPECT_GT(r.movedCaps, 0u);
  EXPECT_EQ(r.tree.root()->children[0]->children[1], r.tree.root()->children[1]->children[1]);
  EXPECT_EQ(r.tree.root()->children[0]->children[1]->name, "bore");
}

TEST(FaceSnapping, ANegativeToleranceIsRefused) {
  EXPECT_THROW(snapFaces(plateAndBoss(5.0), {.tolerance = -1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
