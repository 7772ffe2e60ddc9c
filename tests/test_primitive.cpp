// Tests for primitives/primitive.h: closed-form values, exactness of the
// distance (brute force against parametric surface samples), gradients,
// classification, bounds, volume and area, validation and equality.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/primitive.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::expectNear;
using test::Rng;

constexpr double kTol = 1e-12;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kSqrt2 = std::sqrt(2.0);
const double kSqrt5 = std::sqrt(5.0);

// Maps a local point of a frame (columns u, v, w) at `origin` to world space.
Vec3 world(const Vec3& origin, const Mat3& frame, const Vec3& local) {
  return origin + frame * local;
}

Vec3 gradientAt(const Primitive& prim, const Vec3& p) {
  Vec3 g;
  prim.valueAndGradient(p, g);
  return g;
}

// ---------------------------------------------------------------------------
// Closed forms at chosen points.

TEST(PrimitiveValue, DefaultIsLowerHalfSpace) {
  const Primitive p;
  ASSERT_EQ(p.type(), PrimitiveType::HalfSpace);
  EXPECT_NEAR(p.value(Vec3(5, -3, -2)), 2.0, kTol);
  EXPECT_NEAR(p.value(Vec3(0, 0, 1.5)), -1.5, kTol);
  EXPECT_FALSE(p.isBounded());
  EXPECT_EQ(p.as<Sphere>(), nullptr);
  ASSERT_NE(p.as<HalfSpace>(), nullptr);
}

TEST(PrimitiveValue, HalfSpace) {
  const Vec3 n = Vec3(1, 2, 2) / 3.0;
  const Primitive p = HalfSpace{n, 1.5};
  EXPECT_NEAR(p.value(Vec3::Zero()), 1.5, kTol);  // inside, distance to the plane
  EXPECT_NEAR(p.value(1.5 * n), 0.0, kTol);       // on the plane
  EXPECT_NEAR(p.value(4.0 * n), -2.5, kTol);      // outside along the normal
  const Vec3 t = Vec3(2, -1, 0) / kSqrt5;         // tangent to the plane
  EXPECT_NEAR(p.value(0.5 * n + 7.0 * t), 1.0, kTol);
  expectNear(gradientAt(p, Vec3(3, -1, 4)), -n, kTol);
}

TEST(PrimitiveValue, AxisAlignedBox) {
  const Vec3 c(1, -2, 3);
  const Primitive p = Box{c, Mat3::Identity(), Vec3(1, 2, 3)};
  EXPECT_NEAR(p.value(c), 1.0, kTol);                                // centre: nearest face x
  EXPECT_NEAR(p.value(c + Vec3(1, 0.3, -0.2)), 0.0, kTol);           // on the +x face
  EXPECT_NEAR(p.value(c + Vec3(0.9, 0, 0)), 0.1, kTol);              // inside near a face
  EXPECT_NEAR(p.value(c + Vec3(0, 0, -2.75)), 0.25, kTol);           // inside near the -z face
  EXPECT_NEAR(p.value(c + Vec3(3, 0, 0)), -2.0, kTol);               // outside along an axis
  EXPECT_NEAR(p.value(c + Vec3(2, 3, 0)), -kSqrt2, kTol);            // nearest: an edge
  EXPECT_NEAR(p.value(c + Vec3(-2, -3, 4)), -std::sqrt(3.0), kTol);  // nearest: a corner
  expectNear(gradientAt(p, c + Vec3(3, 0, 0)), Vec3(-1, 0, 0), kTol);
  expectNear(gradientAt(p, c + Vec3(2, 3, 0)), Vec3(-1, -1, 0) / kSqrt2, kTol);
  expectNear(gradientAt(p, c + Vec3(0, 0, -2.75)), Vec3(0, 0, 1), kTol);
}

TEST(PrimitiveValue, RotatedBox) {
  Rng rng(7);
  const Mat3 r = test::randomRotation(rng);
  const Vec3 c(0.5, 1, -1);
  const Primitive p = Box{c, r, Vec3(1, 2, 3)};
  EXPECT_NEAR(p.value(c), 1.0, kTol);
  EXPECT_NEAR(p.value(world(c, r, Vec3(1, 0.3, -0.2))), 0.0, kTol);
  EXPECT_NEAR(p.value(world(c, r, Vec3(0.9, 0, 0))), 0.1, kTol);
  EXPECT_NEAR(p.value(world(c, r, Vec3(0, -5, 0))), -3.0, kTol);
  EXPECT_NEAR(p.value(world(c, r, Vec3(2, 3, 0))), -kSqrt2, kTol);
  EXPECT_NEAR(p.value(world(c, r, Vec3(-2, -3, 4))), -std::sqrt(3.0), kTol);
  expectNear(gradientAt(p, world(c, r, Vec3(0, -5, 0))), r * Vec3(0, 1, 0), kTol);
  expectNear(gradientAt(p, world(c, r, Vec3(0.9, 0, 0))), r * Vec3(-1, 0, 0), kTol);
}

TEST(PrimitiveValue, Cylinder) {
  const Vec3 c(1, 2, 3);
  const Primitive p = Cylinder{c, Vec3::UnitZ(), 2.0, 2.0};
  EXPECT_NEAR(p.value(c), 1.0, kTol);                         // caps are nearest
  EXPECT_NEAR(p.value(c + Vec3(2, 0, 0.5)), 0.0, kTol);       // on the lateral surface
  EXPECT_NEAR(p.value(c + Vec3(0, 1.8, 0)), 0.2, kTol);       // inside near the side
  EXPECT_NEAR(p.value(c + Vec3(0.3, 0, -0.9)), 0.1, kTol);    // inside near a cap
  EXPECT_NEAR(p.value(c + Vec3(0, 0, 3)), -2.0, kTol);        // outside along the axis
  EXPECT_NEAR(p.value(c + Vec3(0, -5, 0)), -3.0, kTol);       // outside radially
  EXPECT_NEAR(p.value(c + Vec3(0, 3, -2)), -kSqrt2, kTol);    // nearest: the bottom rim
  EXPECT_NEAR(p.value(c + Vec3(1.2, 1.6, 1.5)), -0.5, kTol);  // above the top cap
  expectNear(gradientAt(p, c + Vec3(0, 3, -2)), Vec3(0, -1, 1) / kSqrt2, kTol);
  expectNear(gradientAt(p, c + Vec3(0, 0, -3)), Vec3(0, 0, 1), kTol);
  expectNear(gradientAt(p, c + Vec3(0, 1.8, 0)), Vec3(0, -1, 0), kTol);
}

TEST(PrimitiveValue, TiltedCylinder) {
  const Vec3 axis = Vec3(1, 1, 1).normalized();
  const Mat3 f = frameFromAxis(axis);
  const Vec3 c(-1, 0, 2);
  const Primitive p = Cylinder{c, axis, 2.0, 2.0};
  EXPECT_NEAR(p.value(c), 1.0, kTol);
  EXPECT_NEAR(p.value(world(c, f, Vec3(0, 0, 3))), -2.0, kTol);
  EXPECT_NEAR(p.value(world(c, f, Vec3(0, 3, -2))), -kSqrt2, kTol);
  EXPECT_NEAR(p.value(world(c, f, Vec3(-1.8, 0, 0))), 0.2, kTol);
  expectNear(gradientAt(p, world(c, f, Vec3(0, 0, 3))), -axis, kTol);
}

// Frustum: bottom radius 2 at z = -1, top radius 1 at z = +1. The lateral edge
// in the meridian plane runs from (2,-1) to (1,1); its outward normal is (2,1)/sqrt5.
TEST(PrimitiveValue, ConeFrustum) {
  const Vec3 c(0.5, -0.5, 1);
  const Primitive p = Cone{c, Vec3::UnitZ(), 2.0, 1.0, 2.0};
  EXPECT_NEAR(p.value(c), 1.0, kTol);                           // caps at distance 1, side 3/sqrt5
  EXPECT_NEAR(p.value(c + Vec3(1.5, 0, 0)), 0.0, kTol);         // on the lateral surface
  EXPECT_NEAR(p.value(c + Vec3(0, 0, -0.9)), 0.1, kTol);        // inside near the bottom cap
  EXPECT_NEAR(p.value(c + Vec3(0, 1, 0)), 1.0 / kSqrt5, kTol);  // inside near the side
  EXPECT_NEAR(p.value(c + Vec3(0, 0, 3)), -2.0, kTol);          // outside along the axis
  EXPECT_NEAR(p.value(c + Vec3(0, 0, -4)), -3.0, kTol);
  EXPECT_NEAR(p.value(c + Vec3(2, 0, 0)), -1.0 / kSqrt5, kTol);        // outside the side
  EXPECT_NEAR(p.value(c + Vec3(0, 3, -2)), -kSqrt2, kTol);             // nearest: the bottom rim
  EXPECT_NEAR(p.value(c + Vec3(-1.5, 0, 2)), -std::sqrt(1.25), kTol);  // nearest: the top rim
  EXPECT_NEAR(p.value(c + Vec3(0, 0.5, 1.5)), -0.5, kTol);             // above the top cap
  expectNear(gradientAt(p, c + Vec3(2, 0, 0)), -Vec3(2, 0, 1) / kSqrt5, kTol);
  expectNear(gradientAt(p, c + Vec3(0, 3, -2)), Vec3(0, -1, 1) / kSqrt2, kTol);
}

// Pointed cone: radius 1 at z = -1, apex at z = +1.
TEST(PrimitiveValue, PointedCone) {
  const Primitive p = Cone{Vec3::Zero(), Vec3::UnitZ(), 1.0, 0.0, 2.0};
  EXPECT_NEAR(p.value(Vec3::Zero()), 1.0 / kSqrt5, kTol);  // the side is nearer than the base
  EXPECT_NEAR(p.value(Vec3(0, 0, 1)), 0.0, kTol);          // the apex
  EXPECT_NEAR(p.value(Vec3(0, 0, 2)), -1.0, kTol);         // above the apex
  EXPECT_NEAR(p.value(Vec3(0.1, 0, 3)), -std::hypot(0.1, 2.0), kTol);
  EXPECT_NEAR(p.value(Vec3(0, 0, -3)), -2.0, kTol);     // below the base
  EXPECT_NEAR(p.value(Vec3(2, 0, -2)), -kSqrt2, kTol);  // nearest: the base rim
  EXPECT_NEAR(p.value(Vec3(0, 0.1, -0.9)), 0.1, kTol);  // inside near the base
  expectNear(gradientAt(p, Vec3(0, 0, 2)), Vec3(0, 0, -1), kTol);
}

// Inverted frustum (wider at the top) is the mirror image of ConeFrustum, and
// the same solid as a frustum with the axis reversed and the radii swapped.
TEST(PrimitiveValue, InvertedFrustum) {
  const Primitive p = Cone{Vec3::Zero(), Vec3::UnitZ(), 1.0, 2.0, 2.0};
  const Primitive mirror = Cone{Vec3::Zero(), Vec3::UnitZ(), 2.0, 1.0, 2.0};
  const Primitive flipped = Cone{Vec3::Zero(), -Vec3::UnitZ(), 2.0, 1.0, 2.0};
  EXPECT_NEAR(p.value(Vec3(0, 3, 2)), -kSqrt2, kTol);  // nearest: the top (wide) rim
  EXPECT_NEAR(p.value(Vec3(2, 0, 0)), -1.0 / kSqrt5, kTol);
  EXPECT_NEAR(p.value(Vec3(0, 0, 0.9)), 0.1, kTol);
  Rng rng(3);
  for (int i = 0; i < 200; ++i) {
    const Vec3 q(test::uniform(rng, -3, 3), test::uniform(rng, -3, 3), test::uniform(rng, -3, 3));
    EXPECT_NEAR(p.value(q), mirror.value(Vec3(q.x(), q.y(), -q.z())), kTol);
    EXPECT_NEAR(p.value(q), flipped.value(q), kTol);
  }
}

TEST(PrimitiveValue, Sphere) {
  const Vec3 c(1, -1, 2);
  const Primitive p = Sphere{c, 2.0};
  EXPECT_NEAR(p.value(c), 2.0, kTol);
  EXPECT_NEAR(p.value(c + Vec3(0, 2, 0)), 0.0, kTol);
  EXPECT_NEAR(p.value(c + Vec3(0, 0, -1.5)), 0.5, kTol);
  EXPECT_NEAR(p.value(c + Vec3(3, 4, 0)), -3.0, kTol);
  expectNear(gradientAt(p, c + Vec3(3, 4, 0)), -Vec3(0.6, 0.8, 0), kTol);
}

TEST(PrimitiveValue, Torus) {
  const Vec3 c(0, 1, -1);
  const Primitive p = Torus{c, Vec3::UnitZ(), 2.0, 0.5};
  EXPECT_NEAR(p.value(c), -1.5, kTol);                                        // the hole
  EXPECT_NEAR(p.value(c + Vec3(2, 0, 0)), 0.5, kTol);                         // tube centre
  EXPECT_NEAR(p.value(c + Vec3(0, -2.5, 0)), 0.0, kTol);                      // outer equator
  EXPECT_NEAR(p.value(c + Vec3(1.5, 0, 0)), 0.0, kTol);                       // inner equator
  EXPECT_NEAR(p.value(c + Vec3(0, 2, 0.4)), 0.1, kTol);                       // inside near the top
  EXPECT_NEAR(p.value(c + Vec3(0, 0, 3)), 0.5 - std::hypot(2.0, 3.0), kTol);  // on the axis
  EXPECT_NEAR(p.value(c + Vec3(-4, 0, 0)), -1.5, kTol);
  expectNear(gradientAt(p, c + Vec3(0, 2, 0.4)), Vec3(0, 0, -1), kTol);
  expectNear(gradientAt(p, c + Vec3(3.5, 0, 0)), Vec3(-1, 0, 0), kTol);
  expectNear(gradientAt(p, c + Vec3(0.5, 0, 0)), Vec3(1, 0, 0), kTol);  // towards the tube
}

TEST(PrimitiveValue, TiltedTorus) {
  const Vec3 axis = Vec3(0, 3, 4) / 5.0;
  const Mat3 f = frameFromAxis(axis);
  const Primitive p = Torus{Vec3::Zero(), axis, 2.0, 0.5};
  EXPECT_NEAR(p.value(world(Vec3::Zero(), f, Vec3(0, 2, 0.4))), 0.1, kTol);
  EXPECT_NEAR(p.value(world(Vec3::Zero(), f, Vec3(0, 0, 3))), 0.5 - std::hypot(2.0, 3.0), kTol);
  EXPECT_NEAR(p.value(world(Vec3::Zero(), f, Vec3(-2.5, 0, 0))), 0.0, kTol);
}

// ---------------------------------------------------------------------------
// Properties checked on a list of shapes (each its own test).

struct ShapeCase {
  std::string name;
  Primitive prim;
};

void PrintTo(const ShapeCase& c, std::ostream* os) { *os << c.name; }

std::vector<ShapeCase> shapeCases() {
  Rng rng(20240611);
  const Vec3 tilt = Vec3(1, -2, 2) / 3.0;
  std::vector<ShapeCase> cases = {
      {"HalfSpace", HalfSpace{Vec3(2, -1, 2) / 3.0, 0.4}},
      {"Box", Box{Vec3(0.2, 0, -0.3), Mat3::Identity(), Vec3(1, 0.5, 0.75)}},
      {"RotatedBox", Box{Vec3(1, -1, 0.5), test::randomRotation(rng), Vec3(0.6, 1.2, 0.3)}},
      {"Cylinder", Cylinder{Vec3(0, 0.5, 0), Vec3::UnitZ(), 0.8, 1.5}},
      {"TiltedCylinder", Cylinder{Vec3(-1, 0, 1), tilt, 0.5, 2.0}},
      {"FlatCylinder", Cylinder{Vec3::Zero(), Vec3::UnitX(), 1.5, 0.3}},
      {"ConeFrustum", Cone{Vec3(0.3, 0, 0), tilt, 1.0, 0.5, 1.2}},
      {"PointedCone", Cone{Vec3::Zero(), Vec3::UnitZ(), 1.0, 0.0, 1.5}},
      {"PointedDownCone", Cone{Vec3(0, 1, 0), tilt, 0.0, 0.8, 1.0}},
      {"InvertedFrustum", Cone{Vec3::Zero(), Vec3::UnitY(), 0.4, 1.1, 1.0}},
      {"FlatFrustum", Cone{Vec3::Zero(), tilt, 1.5, 1.3, 0.2}},
      {"SteepCone", Cone{Vec3::Zero(), Vec3::UnitZ(), 0.3, 0.1, 2.0}},
      {"StraightCone", Cone{Vec3::Zero(), tilt, 0.7, 0.7, 1.0}},
      {"Sphere", Sphere{Vec3(0.5, -0.5, 1), 0.9}},
      {"Torus", Torus{Vec3::Zero(), Vec3::UnitZ(), 1.0, 0.3}},
      {"TiltedTorus", Torus{Vec3(0.5, 0.5, 0), tilt, 1.2, 0.4}},
      {"HornTorus", Torus{Vec3::Zero(), Vec3(0.6, 0, 0.8), 0.6, 0.6}},
  };
  for (PrimitiveType t : test::allPrimitiveTypes()) {
    for (int i = 0; i < 2; ++i) {
      cases.push_back({"Random" + std::string(primitiveTypeName(t)) + std::to_string(i),
                       test::randomPrimitive(t, rng)});
    }
  }
  return cases;
}

class PrimitiveShapes : public ::testing::TestWithParam<ShapeCase> {
 protected:
  const Primitive& prim() const { return GetParam().prim; }
  // Where random query points are drawn: the bounds grown by a third of the
  // diagonal, or a box around the origin for a half-space.
  Aabb queryBox() const {
    const Aabb b = prim().bounds();
    if (!b.isBounded()) return Aabb{Vec3::Constant(-1.5), Vec3::Constant(1.5)};
    return b.grown(0.3 * b.diagonal());
  }
  double scale() const {
    const Aabb b = prim().bounds();
    return b.isBounded() ? b.diagonal() : 3.0;
  }
};

// |f| is the distance to the surface: never more than the distance to the
// nearest surface sample, and less by at most the sampling's covering radius.
TEST_P(PrimitiveShapes, DistanceMatchesBruteForce) {
  ASSERT_NO_THROW(prim().validate());
  const test::SurfaceSamples s = test::sampleSurface(prim(), 0.008 * scale());
  ASSERT_GT(s.points.size(), 1000u);
  ASSERT_LT(s.cover, 0.01 * scale());
  Rng rng(11);
  const Aabb box = queryBox();
  std::vector<Vec3> bases;  // surface samples in the query box (a half-space's patch is larger)
  for (const Vec3& p : s.points) {
    if (box.contains(p)) bases.push_back(p);
  }
  ASSERT_GT(bases.size(), 100u);
  int inside = 0, outside = 0;
  for (int i = 0; i < 240; ++i) {
    Vec3 q;
    if (i % 2 == 0) {
      q = test::randomPoint(rng, box);
    } else {  // near the surface, where edges and rims matter
      const Vec3& on = bases[std::uniform_int_distribution<std::size_t>(0, bases.size() - 1)(rng)];
      q = on + test::uniform(rng, 0.0, 0.15 * scale()) * test::randomUnit(rng);
    }
    const double f = prim().value(q);
    const double brute = test::nearestSampleDistance(s.points, q);
    (f >= 0 ? inside : outside)++;
    EXPECT_LE(std::abs(f), brute + 1e-9) << "at " << test::str(q);
    EXPECT_LE(brute - std::abs(f), s.cover + 1e-9) << "at " << test::str(q) << " f = " << f;
  }
  EXPECT_GT(inside, 30);
  EXPECT_GT(outside, 30);
}

TEST_P(PrimitiveShapes, GradientMatchesFiniteDifferences) {
  Rng rng(12);
  const Aabb box = queryBox();
  const auto fn = [&](const Vec3& p) { return prim().value(p); };
  int checked = 0;
  const int n = 400;
  for (int i = 0; i < n; ++i) {
    const Vec3 q = test::randomPoint(rng, box);
    if (!test::isSmoothAt(fn, q, 1e-3 * scale())) continue;  // near a crease or the medial axis
    ++checked;
    Vec3 g;
    const double f = prim().valueAndGradient(q, g);
    EXPECT_EQ(f, prim().value(q));
    EXPECT_TRUE(test::vecNear(g, test::numericGradient(fn, q, 1e-6), 1e-6))
        << "at " << test::str(q);
  }
  EXPECT_GE(checked, n * 95 / 100);
}

TEST_P(PrimitiveShapes, GradientHasUnitLength) {
  Rng rng(13);
  const Aabb box = queryBox();
  for (int i = 0; i < 1000; ++i) {
    const Vec3 q = test::randomPoint(rng, box);
    Vec3 g;
    prim().valueAndGradient(q, g);
    EXPECT_NEAR(g.norm(), 1.0, 1e-9) << "at " << test::str(q);
  }
}

TEST_P(PrimitiveShapes, SignMatchesPointInSolid) {
  Rng rng(14);
  const Aabb box = queryBox();
  int inside = 0, outside = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 q = test::randomPoint(rng, box);
    const double f = prim().value(q);
    if (std::abs(f) < 1e-9) continue;
    const bool in = test::insideReference(prim(), q);
    (in ? inside : outside)++;
    EXPECT_EQ(f > 0.0, in) << "at " << test::str(q) << " f = " << f;
  }
  EXPECT_GT(inside, 20);
  EXPECT_GT(outside, 20);
}

TEST_P(PrimitiveShapes, BoundsAreTight) {
  const Aabb b = prim().bounds();
  if (prim().type() == PrimitiveType::HalfSpace) {
    EXPECT_FALSE(prim().isBounded());
    EXPECT_FALSE(b.isBounded());
    EXPECT_FALSE(b.isEmpty());
    EXPECT_TRUE(b.contains(Vec3(1e300, -1e300, 0)));
    return;
  }
  EXPECT_TRUE(prim().isBounded());
  ASSERT_TRUE(b.isBounded());
  const test::SurfaceSamples s = test::sampleSurface(prim(), 0.005 * b.diagonal());
  Aabb hull;
  for (const Vec3& p : s.points) hull.extend(p);
  EXPECT_TRUE(test::vecNear(hull.min.cwiseMax(b.min), hull.min, 1e-9)) << "a sample lies below min";
  EXPECT_TRUE(test::vecNear(hull.max.cwiseMin(b.max), hull.max, 1e-9)) << "a sample lies above max";
  EXPECT_TRUE(test::vecNear(hull.min, b.min, s.cover + 1e-9)) << "min is not tight";
  EXPECT_TRUE(test::vecNear(hull.max, b.max, s.cover + 1e-9)) << "max is not tight";
}

TEST_P(PrimitiveShapes, VolumeMatchesMonteCarlo) {
  if (!prim().isBounded()) {
    EXPECT_EQ(prim().volume(), std::numeric_limits<double>::infinity());
    return;
  }
  const Aabb b = prim().bounds();
  const double boxVolume = b.size().prod();
  Rng rng(15);
  const int n = 300000;
  int hits = 0;
  for (int i = 0; i < n; ++i) hits += test::insideReference(prim(), test::randomPoint(rng, b));
  const double p = static_cast<double>(hits) / n;
  const double sigma = boxVolume * std::sqrt(p * (1 - p) / n);
  EXPECT_NEAR(prim().volume(), p * boxVolume, 5 * sigma);
  EXPECT_LT(5 * sigma, 0.03 * prim().volume());  // the check is sharp enough to mean something
}

// Area from the volume of the shell |f| <= eps: 2 * eps * area up to O(eps^2).
TEST_P(PrimitiveShapes, SurfaceAreaMatchesMonteCarlo) {
  if (!prim().isBounded()) {
    EXPECT_EQ(prim().surfaceArea(), std::numeric_limits<double>::infinity());
    return;
  }
  const double eps = 0.004 * scale();
  const Aabb b = prim().bounds().grown(eps);
  const double boxVolume = b.size().prod();
  Rng rng(16);
  const int n = 400000;
  int hits = 0;
  for (int i = 0; i < n; ++i) hits += std::abs(prim().value(test::randomPoint(rng, b))) <= eps;
  const double p = static_cast<double>(hits) / n;
  const double estimate = p * boxVolume / (2 * eps);
  const double sigma = std::sqrt(p * (1 - p) / n) * boxVolume / (2 * eps);
  EXPECT_NEAR(prim().surfaceArea(), estimate, 5 * sigma + 0.01 * estimate);
  EXPECT_LT(5 * sigma + 0.01 * estimate, 0.06 * estimate);
}

INSTANTIATE_TEST_SUITE_P(Shapes, PrimitiveShapes, ::testing::ValuesIn(shapeCases()),
                         [](const ::testing::TestParamInfo<ShapeCase>& info) {
                           return info.param.name;
                         });

// ---------------------------------------------------------------------------
// Validation.

struct BadCase {
  std::string what;  // expected in the message
  Primitive prim;
};

TEST(PrimitiveValidate, AcceptsGoodParameters) {
  for (const ShapeCase& c : shapeCases()) EXPECT_NO_THROW(c.prim.validate()) << c.name;
  EXPECT_NO_THROW(Primitive(Torus{Vec3::Zero(), Vec3::UnitZ(), 1.0, 1.0}).validate());
  EXPECT_NO_THROW(Primitive(Cone{Vec3::Zero(), Vec3::UnitZ(), 0.0, 1.0, 1.0}).validate());
}

TEST(PrimitiveValidate, RejectsBadParameters) {
  Mat3 sheared = Mat3::Identity();
  sheared.col(1) = Vec3(1, 1, 0).normalized();
  Mat3 leftHanded = Mat3::Identity();
  leftHanded.col(2) = -Vec3::UnitZ();
  const Vec3 z = Vec3::UnitZ();
  const std::vector<BadCase> cases = {
      {"normal", HalfSpace{Vec3(0, 0, 2), 0.0}},
      {"normal", HalfSpace{Vec3::Zero(), 0.0}},
      {"offset", HalfSpace{z, kNaN}},
      {"half size", Box{Vec3::Zero(), Mat3::Identity(), Vec3(1, 0, 1)}},
      {"half size", Box{Vec3::Zero(), Mat3::Identity(), Vec3(1, -1, 1)}},
      {"half size", Box{Vec3::Zero(), Mat3::Identity(), Vec3(1, kNaN, 1)}},
      {"center", Box{Vec3(kNaN, 0, 0), Mat3::Identity(), Vec3::Ones()}},
      {"axis", Box{Vec3::Zero(), 2.0 * Mat3::Identity(), Vec3::Ones()}},
      {"axes", Box{Vec3::Zero(), sheared, Vec3::Ones()}},
      {"axes", Box{Vec3::Zero(), leftHanded, Vec3::Ones()}},
      {"radius", Cylinder{Vec3::Zero(), z, 0.0, 1.0}},
      {"radius", Cylinder{Vec3::Zero(), z, kNaN, 1.0}},
      {"height", Cylinder{Vec3::Zero(), z, 1.0, -1.0}},
      {"axis", Cylinder{Vec3::Zero(), Vec3(0, 1, 1), 1.0, 1.0}},
      {"center", Cylinder{Vec3(0, std::numeric_limits<double>::infinity(), 0), z, 1.0, 1.0}},
      {"radii", Cone{Vec3::Zero(), z, 0.0, 0.0, 1.0}},
      {"radii", Cone{Vec3::Zero(), z, -0.5, 1.0, 1.0}},
      {"radii", Cone{Vec3::Zero(), z, 1.0, kNaN, 1.0}},
      {"height", Cone{Vec3::Zero(), z, 1.0, 0.5, 0.0}},
      {"axis", Cone{Vec3::Zero(), Vec3(kNaN, 0, 1), 1.0, 0.5, 1.0}},
      {"radius", Sphere{Vec3::Zero(), 0.0}},
      {"radius", Sphere{Vec3::Zero(), -1.0}},
      {"center", Sphere{Vec3(0, 0, kNaN), 1.0}},
      {"minor radius", Torus{Vec3::Zero(), z, 1.0, 1.5}},
      {"minor radius", Torus{Vec3::Zero(), z, 1.0, 0.0}},
      {"major radius", Torus{Vec3::Zero(), z, kNaN, 0.5}},
      {"axis", Torus{Vec3::Zero(), Vec3(0.5, 0, 0), 1.0, 0.5}},
  };
  for (const BadCase& c : cases) {
    try {
      c.prim.validate();
      ADD_FAILURE() << primitiveTypeName(c.prim.type()) << " with bad " << c.what
                    << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(c.what), std::string::npos)
          << "message '" << e.what() << "' does not mention " << c.what;
    }
  }
}

// ---------------------------------------------------------------------------
// Equality and names.

// Copies of `p`, each with one parameter moved by `delta`.
std::vector<Primitive> perturbations(const Primitive& p, double delta) {
  std::vector<Primitive> out;
  auto vecs = [&](auto shape, auto member) {
    for (int i = 0; i < 3; ++i) {
      auto s = shape;
      (s.*member)[i] += delta;
      out.push_back(s);
    }
  };
  auto scalar = [&](auto shape, auto member) {
    auto s = shape;
    s.*member += delta;
    out.push_back(s);
  };
  if (const auto* s = p.as<HalfSpace>()) {
    vecs(*s, &HalfSpace::normal);
    scalar(*s, &HalfSpace::offset);
  } else if (const auto* s = p.as<Box>()) {
    vecs(*s, &Box::center);
    vecs(*s, &Box::halfSize);
    for (int k = 0; k < 9; ++k) {
      Box b = *s;
      b.axes(k / 3, k % 3) += delta;
      out.push_back(b);
    }
  } else if (const auto* s = p.as<Cylinder>()) {
    vecs(*s, &Cylinder::center);
    vecs(*s, &Cylinder::axis);
    scalar(*s, &Cylinder::radius);
    scalar(*s, &Cylinder::height);
  } else if (const auto* s = p.as<Cone>()) {
    vecs(*s, &Cone::center);
    vecs(*s, &Cone::axis);
    scalar(*s, &Cone::radiusBottom);
    scalar(*s, &Cone::radiusTop);
    scalar(*s, &Cone::height);
  } else if (const auto* s = p.as<Sphere>()) {
    vecs(*s, &Sphere::center);
    scalar(*s, &Sphere::radius);
  } else if (const auto* s = p.as<Torus>()) {
    vecs(*s, &Torus::center);
    vecs(*s, &Torus::axis);
    scalar(*s, &Torus::majorRadius);
    scalar(*s, &Torus::minorRadius);
  }
  return out;
}

TEST(PrimitiveEquality, EveryParameterCounts) {
  Rng rng(21);
  for (PrimitiveType t : test::allPrimitiveTypes()) {
    const Primitive p = test::randomPrimitive(t, rng);
    const Primitive copy = p;
    EXPECT_TRUE(p == copy);
    EXPECT_TRUE(p.approxEqual(copy, 0.0));
    const std::vector<Primitive> moved = perturbations(p, 1e-3);
    ASSERT_GE(moved.size(), 4u);
    for (std::size_t i = 0; i < moved.size(); ++i) {
      SCOPED_TRACE(std::string(primitiveTypeName(t)) + " parameter #" + std::to_string(i));
      EXPECT_FALSE(p == moved[i]);
      EXPECT_FALSE(p.approxEqual(moved[i], 0.5e-3));
      EXPECT_TRUE(p.approxEqual(moved[i], 2e-3));
      EXPECT_TRUE(moved[i].approxEqual(p, 2e-3));
    }
  }
}

TEST(PrimitiveEquality, DifferentTypesDiffer) {
  const Primitive sphere = Sphere{Vec3::Zero(), 1.0};
  const Primitive cylinder = Cylinder{Vec3::Zero(), Vec3::UnitZ(), 1.0, 1.0};
  const Primitive cone =
      Cone{Vec3::Zero(), Vec3::UnitZ(), 1.0, 1.0, 1.0};  // same solid as cylinder
  EXPECT_FALSE(sphere.approxEqual(cylinder, 1e9));
  EXPECT_FALSE(cylinder.approxEqual(cone, 1e9));
  EXPECT_FALSE(cylinder == cone);
  const Primitive nan = Sphere{Vec3::Zero(), kNaN};
  EXPECT_FALSE(nan.approxEqual(nan, 1.0));
}

TEST(PrimitiveNames, RoundTrip) {
  const std::vector<std::pair<PrimitiveType, std::string>> names = {
      {PrimitiveType::HalfSpace, "halfspace"}, {PrimitiveType::Box, "box"},
      {PrimitiveType::Cylinder, "cylinder"},   {PrimitiveType::Cone, "cone"},
      {PrimitiveType::Sphere, "sphere"},       {PrimitiveType::Torus, "torus"}};
  Rng rng(22);
  for (const auto& [type, name] : names) {
    EXPECT_EQ(primitiveTypeName(type), name);
    EXPECT_EQ(primitiveTypeFromName(name), type);
    EXPECT_EQ(test::randomPrimitive(type, rng).type(), type);
  }
  EXPECT_THROW(primitiveTypeFromName("Sphere"), std::invalid_argument);
  EXPECT_THROW(primitiveTypeFromName(""), std::invalid_argument);
  EXPECT_THROW(primitiveTypeFromName("half-space"), std::invalid_argument);
  try {
    primitiveTypeFromName("pyramid");
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pyramid"), std::string::npos);
  }
}

TEST(PrimitiveType, MatchesShapeAlternative) {
  EXPECT_EQ(Primitive(HalfSpace{}).type(), PrimitiveType::HalfSpace);
  EXPECT_EQ(Primitive(Box{}).type(), PrimitiveType::Box);
  EXPECT_EQ(Primitive(Cylinder{}).type(), PrimitiveType::Cylinder);
  EXPECT_EQ(Primitive(Cone{}).type(), PrimitiveType::Cone);
  EXPECT_EQ(Primitive(Sphere{}).type(), PrimitiveType::Sphere);
  EXPECT_EQ(Primitive(Torus{}).type(), PrimitiveType::Torus);
  const Primitive p = PrimitiveShape(Sphere{Vec3(1, 2, 3), 4.0});
  ASSERT_NE(p.as<Sphere>(), nullptr);
  EXPECT_EQ(p.as<Sphere>()->radius, 4.0);
  EXPECT_EQ(p.as<Torus>(), nullptr);
}

TEST(PrimitiveValue, ValueOnlyAndBatchedPathsGiveTheGradientPathsValues) {
  Rng rng(23);
  for (const PrimitiveType type : test::allPrimitiveTypes()) {
    for (int k = 0; k < 20; ++k) {
      const Primitive prim = test::randomPrimitive(type, rng);
      std::vector<Vec3> points;
      for (int i = 0; i < 500; ++i) {
        points.push_back(test::randomPoint(rng, Aabb{Vec3::Constant(-4), Vec3::Constant(4)}));
      }
      points.push_back(prim.bounds().isBounded() ? prim.bounds().center() : Vec3::Zero());
      std::vector<double> out(points.size());
      prim.values(points, out);
      for (std::size_t i = 0; i < points.size(); ++i) {
        Vec3 g;
        const double f = prim.valueAndGradient(points[i], g);
        ASSERT_EQ(prim.value(points[i]), f) << primitiveTypeName(type);
        ASSERT_EQ(out[i], f) << primitiveTypeName(type);
      }
    }
  }
}

}  // namespace
}  // namespace csgvox
