// Cuts pushed through a skin thinner than a voxel (optimize/skin_cuts.h), on
// primitives whose right answer follows from the geometry: a face that stops
// `gap` < snap short of the solid's end moves one snap past the exit, which
// is sampled in steps of snap / 16.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "optimize/skin_cuts.h"

namespace csgvox {
namespace {

constexpr double kSnap = 0.1;

// The cube [-1, 1]^3.
CsgTree cube() {
  Box b;
  b.halfSize = Vec3::Ones();
  return CsgTree::leaf(b, "cube");
}

// A hole along z of radius 0.3 whose ends stop 0.04 short of the cube's faces.
Cylinder shortHole() {
  Cylinder c;
  c.radius = 0.3;
  c.height = 1.92;
  return c;
}

double topOf(const Cylinder& c) { return c.center.z() + 0.5 * c.height; }
double bottomOf(const Cylinder& c) { return c.center.z() - 0.5 * c.height; }

// A copy: the tree is often a temporary.
Cylinder cylinderOf(const CsgTree& t) {
  const Cylinder* c = t.root()->primitive.as<Cylinder>();
  EXPECT_NE(c, nullptr);
  return c ? *c : Cylinder{};
}

TEST(MostlyScanned, NeedsMoreThanHalfOfTheProbes) {
  const ScannedAt nearTop = [](const Vec3& p) { return p.z() > 0.5; };
  const std::vector<Vec3> threeOfFive{Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 0),
                                      Vec3(0, 0, 0)};
  const std::vector<Vec3> twoOfFour{Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 0), Vec3(0, 0, 0)};
  EXPECT_TRUE(mostlyScanned(nearTop, threeOfFive));
  EXPECT_FALSE(mostlyScanned(nearTop, twoOfFour));
  EXPECT_FALSE(mostlyScanned(nearTop, {}));
  EXPECT_FALSE(mostlyScanned(ScannedAt{}, threeOfFive));
}

TEST(ThroughSkin, PushesBothEndsOfAHoleThroughTheCube) {
  const CsgTree grown = throughSkin(CsgTree::leaf(shortHole(), "hole"), cube(), kSnap, {});
  const Cylinder c = cylinderOf(grown);
  // Exit 0.04 sampled at 7 / 16 snap, plus one snap.
  EXPECT_GT(topOf(c), 1.0 + kSnap);
  EXPECT_LE(topOf(c), 1.0 + kSnap + kSnap / 16 + 1e-12);
  EXPECT_LT(bottomOf(c), -1.0 - kSnap);
  EXPECT_GE(bottomOf(c), -1.0 - kSnap - kSnap / 16 - 1e-12);
  EXPECT_DOUBLE_EQ(c.radius, 0.3);
  EXPECT_TRUE(c.axis.isApprox(Vec3::UnitZ()));
  EXPECT_EQ(grown.root()->name, "hole");
}

TEST(ThroughSkin, KeepsAFaceWhoseSkinIsScanned) {
  // Scan points on the cube's top face: the top skin is a real thin wall.
  const ScannedAt topScanned = [](const Vec3& p) { return std::abs(p.z() - 1.0) < 0.02; };
  const Cylinder c = cylinderOf(throughSkin(CsgTree::leaf(shortHole()), cube(), kSnap, topScanned));
  EXPECT_DOUBLE_EQ(topOf(c), 0.96);
  EXPECT_LT(bottomOf(c), -1.0 - kSnap);
}

TEST(ThroughSkin, LeavesAHoleThatStopsFartherThanSnap) {
  Cylinder blind = shortHole();
  blind.height = 1.6;  // ends 0.2 = 2 snap short of the faces
  const Cylinder c = cylinderOf(throughSkin(CsgTree::leaf(blind), cube(), kSnap, {}));
  EXPECT_DOUBLE_EQ(c.height, 1.6);
  EXPECT_DOUBLE_EQ(c.center.z(), 0.0);
}

TEST(ThroughSkin, OffWithoutSnapOrForATreeTool) {
  EXPECT_DOUBLE_EQ(cylinderOf(throughSkin(CsgTree::leaf(shortHole()), cube(), 0.0, {})).height,
                   1.92);
  const CsgTree pair = CsgTree::unite({CsgTree::leaf(shortHole()), CsgTree::leaf(Sphere{})});
  const CsgTree same = throughSkin(pair, cube(), kSnap, {});
  EXPECT_EQ(same.root(), pair.root());
}

TEST(ThroughSkin, GoesThroughTheCurvedSurfaceOfAShaft) {
  // A shaft along x of radius 1; a cross hole along z of radius 0.2 whose
  // ends stop 0.03 short of the shaft's top and bottom lines. The skin is
  // thickest (0.03) over the hole's centre line y = 0, thinner at its rim.
  Cylinder shaft;
  shaft.axis = Vec3::UnitX();
  shaft.radius = 1.0;
  shaft.height = 4.0;
  Cylinder hole;
  hole.radius = 0.2;
  hole.height = 1.94;
  const Cylinder c = cylinderOf(throughSkin(CsgTree::leaf(hole), CsgTree::leaf(shaft), kSnap, {}));
  // One snap past the farthest exit, over y = 0.
  EXPECT_GT(topOf(c), 1.0 + kSnap);
  EXPECT_LE(topOf(c), 1.0 + kSnap + kSnap / 16 + 1e-12);
  EXPECT_NEAR(bottomOf(c), -topOf(c), 1e-12);
}

TEST(ThroughSkin, AConeRunsOnAlongItsSlope) {
  Cone cone;
  cone.radiusBottom = 0.2;
  cone.radiusTop = 0.4;
  cone.height = 1.92;
  const CsgTree grown = throughSkin(CsgTree::leaf(cone), cube(), kSnap, {});
  const Cone* g = grown.root()->primitive.as<Cone>();
  ASSERT_NE(g, nullptr);
  const double top = g->center.z() + 0.5 * g->height;
  EXPECT_GT(top, 1.0 + kSnap);
  EXPECT_LE(top, 1.0 + kSnap + kSnap / 16 + 1e-12);
  // The same lateral surface: radius 0.3 at z = 0, slope 0.2 / 1.92.
  const double slope = (g->radiusTop - g->radiusBottom) / g->height;
  EXPECT_NEAR(slope, 0.2 / 1.92, 1e-12);
  EXPECT_NEAR(g->radiusBottom + slope * (0.0 - (g->center.z() - 0.5 * g->height)), 0.3, 1e-12);
}

TEST(ThroughSkin, MovesOnlyTheBoxFaceInTheSkin) {
  // A pocket from z = 0 to z = 0.96: only its top face is in the skin.
  Box pocket;
  pocket.center = Vec3(0, 0, 0.48);
  pocket.halfSize = Vec3(0.3, 0.3, 0.48);
  const CsgTree grown = throughSkin(CsgTree::leaf(pocket), cube(), kSnap, {});
  const Box* b = grown.root()->primitive.as<Box>();
  ASSERT_NE(b, nullptr);
  const double top = b->center.z() + b->halfSize.z(), bottom = b->center.z() - b->halfSize.z();
  EXPECT_GT(top, 1.0 + kSnap);
  EXPECT_LE(top, 1.0 + kSnap + kSnap / 16 + 1e-12);
  EXPECT_NEAR(bottom, 0.0, 1e-12);
  EXPECT_NEAR(b->halfSize.x(), 0.3, 1e-12);
  EXPECT_NEAR(b->halfSize.y(), 0.3, 1e-12);
}

TEST(ThroughCut, GrowsABoxFaceTwoSnapsPastTheRoot) {
  Box pocket;
  pocket.center = Vec3(0, 0, 0.5);
  pocket.halfSize = Vec3(0.3, 0.3, 0.46);  // from z = 0.04 to 0.96
  const CsgTree grown = throughCut(CsgTree::leaf(pocket), cube(), kSnap, {});
  const Box* b = grown.root()->primitive.as<Box>();
  ASSERT_NE(b, nullptr);
  EXPECT_NEAR(b->center.z() + b->halfSize.z(), 1.0 + 2 * kSnap, 1e-12);
  EXPECT_NEAR(b->center.z() - b->halfSize.z(), 0.04, 1e-12);
  // A scanned outer face keeps the wall; a cylinder tool is left alone.
  const ScannedAt topScanned = [](const Vec3& p) { return std::abs(p.z() - 1.0) < 0.02; };
  const CsgTree kept = throughCut(CsgTree::leaf(pocket), cube(), kSnap, topScanned);
  EXPECT_NEAR(kept.root()->primitive.as<Box>()->halfSize.z(), 0.46, 1e-12);
  EXPECT_DOUBLE_EQ(cylinderOf(throughCut(CsgTree::leaf(shortHole()), cube(), kSnap, {})).height,
                   1.92);
}

}  // namespace
}  // namespace csgvox
