#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/nearest_neighbors.h"
#include "mesh/surface_sampler.h"

namespace csgvox {
namespace {

CsgTree plateWithHoles() {
  std::vector<CsgTree> ops{
      CsgTree::leaf(Box{Vec3(0, 0, 2.5), Mat3::Identity(), Vec3(40, 30, 2.5)}, "plate")};
  for (double x : {-30.0, 30.0}) {
    for (double y : {-20.0, 20.0}) {
      ops.push_back(CsgTree::leaf(Cylinder{Vec3(x, y, 2.5), Vec3::UnitZ(), 4.0, 7.0}));
    }
  }
  return CsgTree::subtract(ops);
}

double plateArea() {
  const double pi = std::numbers::pi;
  return 2 * (80 * 60 + 80 * 5 + 60 * 5) - 4 * 2 * pi * 16 + 4 * 2 * pi * 4 * 5;
}

TEST(SurfaceSampler, PointsLieOnTheSurfaceWithOutwardNormals) {
  const CsgTree tree = plateWithHoles();
  SampleOptions o;
  o.points = 20000;
  const SurfaceSample s = sampleSurface(tree, o);
  ASSERT_EQ(s.cloud.size(), 20000u);
  ASSERT_TRUE(s.cloud.hasNormals());
  const double d = tree.bounds().diagonal();
  int agreeing = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Vec3& p = s.cloud.points[i];
    const Vec3& n = s.cloud.normals[i];
    EXPECT_LT(std::abs(tree.value(p)), 1e-9 * d);
    EXPECT_NEAR(n.norm(), 1.0, 1e-9);
    // Outward: a small step along the normal leaves the solid, against it enters.
    EXPECT_LT(tree.value(p + 1e-3 * n), 0.0);
    EXPECT_GT(tree.value(p - 1e-3 * n), 0.0);
    const Vec3 g = tree.evaluate(p - 1e-4 * n).gradient;
    agreeing += (-g).dot(n) > 0.999;
  }
  EXPECT_GT(agreeing, 0.99 * 20000);
}

TEST(SurfaceSampler, HoleWallsAreSampledWithInwardFacingNormals) {
  const CsgTree tree = plateWithHoles();
  const SurfaceSample s = sampleSurface(tree, {});
  ASSERT_EQ(s.source.size(), s.cloud.size());
  int onWall = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Vec3& p = s.cloud.points[i];
    const Vec3 c(p.x() < 0 ? -30 : 30, p.y() < 0 ? -20 : 20, p.z());
    const bool wall = std::abs((p - c).norm() - 4.0) < 1e-9;
    // The ground-truth segmentation: leaf 0 is the plate, 1-4 the holes.
    EXPECT_EQ(s.source[i] != 0, wall);
    if (wall) {
      ++onWall;
      // The wall's outward normal (as seen from the solid) points to the axis.
      EXPECT_GT(s.cloud.normals[i].dot((c - p).normalized()), 0.999);
    }
  }
  // Expected share of the wall area.
  const double wall = 4 * 2 * std::numbers::pi * 4 * 5;
  EXPECT_NEAR(double(onWall) / s.cloud.size(), wall / plateArea(), 0.01);
}

TEST(SurfaceSampler, AreaEstimateMatchesAnalyticArea) {
  EXPECT_NEAR(sampleSurface(plateWithHoles(), {}).surfaceArea / plateArea(), 1.0, 0.01);
  const Torus t{Vec3(1, 2, 3), Vec3(0, 0.6, 0.8), 5.0, 1.5};
  EXPECT_NEAR(sampleSurface(CsgTree::leaf(t), {}).surfaceArea / Primitive(t).surfaceArea(), 1.0,
              0.01);
  const Cone c{Vec3(0, 0, 0), Vec3(1, 0, 0), 3.0, 1.0, 4.0};
  EXPECT_NEAR(sampleSurface(CsgTree::leaf(c), {}).surfaceArea / Primitive(c).surfaceArea(), 1.0,
              0.01);
}

TEST(SurfaceSampler, InternalFacesOfTouchingOperandsAreNotSampled) {
  // Two boxes sharing the face x = 0: the shared face is inside the union.
  const CsgTree tree =
      CsgTree::unite({CsgTree::leaf(Box{Vec3(-1, 0, 0), Mat3::Identity(), Vec3(1, 1, 1)}),
                      CsgTree::leaf(Box{Vec3(1, 0, 0), Mat3::Identity(), Vec3(1, 1, 1)})});
  const SurfaceSample s = sampleSurface(tree, {});
  for (const Vec3& p : s.cloud.points) {
    EXPECT_FALSE(std::abs(p.x()) < 1e-9 && std::abs(p.y()) < 0.999 && std::abs(p.z()) < 0.999);
  }
  EXPECT_NEAR(s.surfaceArea / 40.0, 1.0, 0.01);  // 4x2x2 box: 2*(8+8+4)
}

TEST(SurfaceSampler, HalfSpacesAreSampledWhereTheyBoundTheSolid) {
  // A cube with one corner cut off by a plane.
  const Vec3 n = Vec3(1, 1, 1).normalized();
  const CsgTree tree =
      CsgTree::intersect({CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(1, 1, 1)}),
                          CsgTree::leaf(HalfSpace{n, n.dot(Vec3(1, 1, 0))})});
  const SurfaceSample s = sampleSurface(tree, {});
  int onCut = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    if (std::abs(n.dot(s.cloud.points[i]) - n.dot(Vec3(1, 1, 0))) < 1e-9) {
      ++onCut;
      EXPECT_GT(s.cloud.normals[i].dot(n), 0.999);
    }
  }
  // The cut is an equilateral triangle with side sqrt(2): area sqrt(3)/2.
  // The cube loses three right triangles of area 1/2 each.
  const double cut = std::sqrt(3.0) / 2.0, total = 24.0 - 1.5 + cut;
  EXPECT_NEAR(double(onCut) / s.cloud.size(), cut / total, 0.01);
}

TEST(SurfaceSampler, SameSeedSameScanOtherSeedOtherScan) {
  SampleOptions o;
  o.points = 3000;
  o.noise = 0.002;
  const SurfaceSample a = sampleSurface(plateWithHoles(), o);
  const SurfaceSample b = sampleSurface(plateWithHoles(), o);
  o.seed = 2;
  const SurfaceSample c = sampleSurface(plateWithHoles(), o);
  ASSERT_EQ(a.cloud.size(), b.cloud.size());
  for (std::size_t i = 0; i < a.cloud.size(); ++i) {
    ASSERT_EQ(a.cloud.points[i], b.cloud.points[i]);
    ASSERT_EQ(a.cloud.normals[i], b.cloud.normals[i]);
  }
  EXPECT_NE(a.cloud.points[0], c.cloud.points[0]);
}

TEST(SurfaceSampler, NoiseHasTheRequestedSigma) {
  // On a large sphere the distance to the surface is the radial noise component.
  const Sphere sphere{Vec3(1, 2, 3), 10.0};
  SampleOptions o;
  o.points = 20000;
  o.noise = 0.005;
  const SurfaceSample s = sampleSurface(CsgTree::leaf(sphere), o);
  double sum2 = 0.0;
  for (const Vec3& p : s.cloud.points) sum2 += std::pow(Primitive(sphere).value(p), 2);
  const double sigma = o.noise * s.diagonal;
  EXPECT_NEAR(std::sqrt(sum2 / s.cloud.size()) / sigma, 1.0, 0.03);
}

TEST(SurfaceSampler, DroppedPatchesLeaveHoles) {
  SampleOptions o;
  o.points = 20000;
  const SurfaceSample full = sampleSurface(plateWithHoles(), o);
  o.dropPatches = 3;
  o.patchRadius = 0.05;
  const SurfaceSample holed = sampleSurface(plateWithHoles(), o);
  ASSERT_EQ(holed.cloud.size(), 20000u);
  // Some surface point is now far from every scan point: the largest gap is
  // about the patch radius, while the full scan has no gap larger than a few
  // sample spacings.
  const NearestNeighbors fullIndex(full.cloud.points), holedIndex(holed.cloud.points);
  double gapHoled = 0.0, gapFull = 0.0;
  const SurfaceSample probe = sampleSurface(plateWithHoles(), SampleOptions{5000, 0, 0, 0.05, 7});
  for (const Vec3& p : probe.cloud.points) {
    double d2;
    holedIndex.nearest(p, &d2);
    gapHoled = std::max(gapHoled, std::sqrt(d2));
    fullIndex.nearest(p, &d2);
    gapFull = std::max(gapFull, std::sqrt(d2));
  }
  EXPECT_GT(gapHoled, 0.6 * o.patchRadius * full.diagonal);
  EXPECT_LT(gapFull, 0.4 * o.patchRadius * full.diagonal);
}

TEST(SurfaceSampler, RejectsUnsampleableTrees) {
  EXPECT_THROW(sampleSurface(CsgTree(), {}), std::invalid_argument);
  EXPECT_THROW(sampleSurface(CsgTree::leaf(HalfSpace{}), {}), std::invalid_argument);
  // Two disjoint spheres intersected: an empty solid.
  const CsgTree empty = CsgTree::intersect(
      {CsgTree::leaf(Sphere{Vec3(0, 0, 0), 1}), CsgTree::leaf(Sphere{Vec3(5, 0, 0), 1})});
  EXPECT_THROW(sampleSurface(empty, {}), std::invalid_argument);
}

// A primitive thousands of times wider than the part (a nearly flat face
// fitted as a cylinder of radius 4000 on a part 10 across, as on
// InverseCSG part 148): sampling its whole surface almost never hits the
// part, and the sampler used to give up with "no boundary to sample".
TEST(SurfaceSampler, PrimitivesMuchWiderThanThePartAreSampledNearIt) {
  const double r = 4000.0;
  const CsgTree tree =
      CsgTree::subtract({CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(5, 5, 5)}),
                         CsgTree::leaf(Cylinder{Vec3(3.0 - r, 0, 0), Vec3::UnitZ(), r, 20.0}),
                         CsgTree::leaf(Sphere{Vec3(0, 0, -5.0 - r), r + 1.0})});
  SampleOptions o;
  o.points = 20000;
  const SurfaceSample s = sampleSurface(tree, o);
  ASSERT_EQ(s.cloud.size(), o.points);
  const double d = tree.bounds().diagonal();
  std::size_t onCylinder = 0, onSphere = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    EXPECT_LT(std::abs(tree.value(s.cloud.points[i])), 1e-9 * d);
    onCylinder += s.source[i] == 1;
    onSphere += s.source[i] == 2;
  }
  // Still uniform: each face gets its share of the boundary's area. The
  // solid is about x in [3, 5], z in [-4, 5]: the cylinder's face about
  // 10 x 9, the sphere's 2 x 10, the whole boundary about 2 x 90 + 2 x 20 +
  // 2 x 18.
  const double cylinderShare = 90.0 / 256.0, sphereShare = 20.0 / 256.0;
  EXPECT_NEAR(double(onCylinder) / double(o.points), cylinderShare, 0.02);
  EXPECT_NEAR(double(onSphere) / double(o.points), sphereShare, 0.02);
  EXPECT_NEAR(s.surfaceArea, 256.0, 256.0 * 0.05);
}

// The same for a cone (a nearly flat face fitted as a frustum of radius ~955
// whose apex lies thousands of units away, as on a scanner scan of the
// bundled rotated_block: `eval` of the job's own tree gave up with "no
// boundary to sample").
TEST(SurfaceSampler, ConesMuchWiderThanThePartAreSampledNearIt) {
  const double r = 955.0;
  // The cone's axis along z, its side passing through x = 3 at z = 0,
  // tilted by its radii 955 -> 956 over the height 20.
  const CsgTree tree = CsgTree::subtract(
      {CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(5, 5, 5)}),
       CsgTree::leaf(Cone{Vec3(3.0 - r - 0.5, 0, 0), Vec3::UnitZ(), r, r + 1.0, 20.0})});
  SampleOptions o;
  o.points = 20000;
  const SurfaceSample s = sampleSurface(tree, o);
  ASSERT_EQ(s.cloud.size(), o.points);
  const double d = tree.bounds().diagonal();
  std::size_t onCone = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    EXPECT_LT(std::abs(tree.value(s.cloud.points[i])), 1e-9 * d);
    onCone += s.source[i] == 1;
  }
  // The solid is about x in [3, 5] (the cone's side at x = 3 +- 0.25):
  // the cone's face about 10 x 10 of a boundary of about 2 x 100 + 4 x 20.
  EXPECT_NEAR(double(onCone) / double(o.points), 100.0 / 280.0, 0.02);
  EXPECT_NEAR(s.surfaceArea, 280.0, 280.0 * 0.05);
}

}  // namespace
}  // namespace csgvox
