// clippedSolid: the primitive's value equals the unbounded solid's exact
// signed distance at every point of the box, for every kind of surface.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "core/clipped_solid.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::randomPoint;
using test::randomUnit;
using test::Rng;
using test::uniform;

// The unbounded solids' exact signed distances (>= 0 inside), written here
// independently of the library.
double planeDistance(const PlaneSurface& s, const Vec3& p) { return s.offset - s.normal.dot(p); }

double cylinderDistance(const CylinderSurface& s, const Vec3& p) {
  const Vec3 d = p - s.axisPoint;
  return s.radius - (d - d.dot(s.axisDir) * s.axisDir).norm();
}

// One-sided cone: in the meridian half-plane (z, rho) the solid is the wedge
// between the axis and the generating ray t·(cos a, sin a), t >= 0. Behind
// the ray's start (the apex) the nearest point of the surface is the apex.
double coneDistance(const ConeSurface& s, const Vec3& p) {
  const Vec3 d = p - s.apex;
  const double z = d.dot(s.axisDir);
  const double rho = (d - z * s.axisDir).norm();
  const double c = std::cos(s.halfAngle), sn = std::sin(s.halfAngle);
  if (z * c + rho * sn <= 0.0) return -d.norm();
  return z * sn - rho * c;
}

double sphereDistance(const SphereSurface& s, const Vec3& p) {
  return s.radius - (p - s.center).norm();
}

double torusDistance(const TorusSurface& s, const Vec3& p) {
  const Vec3 d = p - s.center;
  const double z = d.dot(s.axisDir);
  const double rho = (d - z * s.axisDir).norm();
  return s.minorRadius - std::hypot(rho - s.majorRadius, z);
}

double unboundedDistance(const SurfaceShape& shape, const Vec3& p) {
  switch (static_cast<SurfaceType>(shape.index())) {
    case SurfaceType::Plane:
      return planeDistance(std::get<PlaneSurface>(shape), p);
    case SurfaceType::Cylinder:
      return cylinderDistance(std::get<CylinderSurface>(shape), p);
    case SurfaceType::Cone:
      return coneDistance(std::get<ConeSurface>(shape), p);
    case SurfaceType::Sphere:
      return sphereDistance(std::get<SphereSurface>(shape), p);
    case SurfaceType::Torus:
      return torusDistance(std::get<TorusSurface>(shape), p);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

Aabb randomBox(Rng& rng, double scale) {
  Aabb box;
  const Vec3 c(uniform(rng, -scale, scale), uniform(rng, -scale, scale),
               uniform(rng, -scale, scale));
  box.min = c - Vec3(uniform(rng, 0.05, 1), uniform(rng, 0.05, 1), uniform(rng, 0.05, 1)) * scale;
  box.max = c + Vec3(uniform(rng, 0.05, 1), uniform(rng, 0.05, 1), uniform(rng, 0.05, 1)) * scale;
  return box;
}

Vec3 randomPointNear(Rng& rng, const Aabb& box) {
  return box.center() +
         Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)) * box.diagonal();
}

SurfaceShape randomSurface(SurfaceType type, Rng& rng, const Aabb& box) {
  const double d = box.diagonal();
  switch (type) {
    case SurfaceType::Plane: {
      const Vec3 n = randomUnit(rng);
      return PlaneSurface{n, n.dot(randomPointNear(rng, box))};
    }
    case SurfaceType::Cylinder:
      return CylinderSurface{randomPointNear(rng, box), randomUnit(rng), uniform(rng, 0.01, 1) * d};
    case SurfaceType::Cone:
      return ConeSurface{randomPointNear(rng, box), randomUnit(rng), uniform(rng, 0.05, 1.5)};
    case SurfaceType::Sphere:
      return SphereSurface{randomPointNear(rng, box), uniform(rng, 0.01, 1) * d};
    case SurfaceType::Torus: {
      const double major = uniform(rng, 0.05, 1) * d;
      return TorusSurface{randomPointNear(rng, box), randomUnit(rng), major,
                          uniform(rng, 0.05, 1) * major};
    }
  }
  return PlaneSurface{};
}

// Length scale of the problem: values are compared within 1e-9 of it (or of
// the value itself when larger).
double problemScale(const SurfaceShape& shape, const Aabb& box) {
  const Vec3 c = box.center();
  return box.diagonal() + std::visit(
                              [&c](const auto& s) -> double {
                                using S = std::decay_t<decltype(s)>;
                                if constexpr (std::is_same_v<S, PlaneSurface>) {
                                  return std::abs(s.offset) + c.norm();
                                } else if constexpr (std::is_same_v<S, CylinderSurface>) {
                                  return s.radius + (s.axisPoint - c).norm();
                                } else if constexpr (std::is_same_v<S, ConeSurface>) {
                                  return (s.apex - c).norm();
                                } else if constexpr (std::is_same_v<S, SphereSurface>) {
                                  return s.radius + (s.center - c).norm();
                                } else {
                                  return s.majorRadius + (s.center - c).norm();
                                }
                              },
                              shape);
}

// Samples of the box: its eight corners, its centre and random points.
std::vector<Vec3> boxSamples(Rng& rng, const Aabb& box, int randomCount) {
  std::vector<Vec3> points;
  for (int k = 0; k < 8; ++k) {
    points.emplace_back(k & 1 ? box.max.x() : box.min.x(), k & 2 ? box.max.y() : box.min.y(),
                        k & 4 ? box.max.z() : box.min.z());
  }
  points.push_back(box.center());
  for (int i = 0; i < randomCount; ++i) points.push_back(randomPoint(rng, box));
  return points;
}

// Checks value == unbounded distance at the samples; returns the number of
// samples on each side (inside, outside) so callers can check both occur.
std::pair<int, int> expectExactInBox(const SurfaceShape& shape, const Aabb& box, Rng& rng,
                                     int randomCount = 400) {
  const Primitive prim = clippedSolid(shape, box);
  const double scale = problemScale(shape, box);
  int inside = 0, outside = 0;
  for (const Vec3& p : boxSamples(rng, box, randomCount)) {
    const double expected = unboundedDistance(shape, p);
    const double got = prim.value(p);
    EXPECT_NEAR(got, expected, 1e-9 * std::max(std::abs(expected), scale))
        << surfaceTypeName(static_cast<SurfaceType>(shape.index())) << " at " << test::str(p)
        << " box " << test::str(box.min) << " " << test::str(box.max);
    (expected >= 0.0 ? inside : outside) += 1;
  }
  return {inside, outside};
}

TEST(ClippedSolid, MatchesTheUnboundedDistanceInTheBoxForEveryType) {
  Rng rng(20160501);
  for (SurfaceType type : {SurfaceType::Plane, SurfaceType::Cylinder, SurfaceType::Cone,
                           SurfaceType::Sphere, SurfaceType::Torus}) {
    int inside = 0, outside = 0;
    for (int trial = 0; trial < 60; ++trial) {
      const double scale = std::pow(10.0, uniform(rng, -2, 3));
      const Aabb box = randomBox(rng, scale);
      const auto [in, out] = expectExactInBox(randomSurface(type, rng, box), box, rng);
      inside += in;
      outside += out;
    }
    // Both sides of every kind of surface were exercised.
    EXPECT_GT(inside, 1000) << surfaceTypeName(type);
    EXPECT_GT(outside, 1000) << surfaceTypeName(type);
  }
}

TEST(ClippedSolid, PlaneIsTheHalfSpaceBehindItsNormal) {
  const PlaneSurface plane{Vec3::UnitX(), 2.0};
  const Primitive prim = clippedSolid(plane, Aabb{Vec3::Zero(), Vec3::Ones()});
  ASSERT_NE(prim.as<HalfSpace>(), nullptr);
  EXPECT_EQ(prim.as<HalfSpace>()->normal, Vec3::UnitX());
  EXPECT_EQ(prim.as<HalfSpace>()->offset, 2.0);
  EXPECT_DOUBLE_EQ(prim.value(Vec3(0.5, 0, 0)), 1.5);   // behind the normal: inside
  EXPECT_DOUBLE_EQ(prim.value(Vec3(3.0, 0, 0)), -1.0);  // in front: outside
}

TEST(ClippedSolid, SphereAndTorusAreUnchanged) {
  const Aabb box{Vec3::Constant(-1), Vec3::Constant(1)};
  const Primitive s = clippedSolid(SphereSurface{Vec3(1, 2, 3), 0.5}, box);
  ASSERT_NE(s.as<Sphere>(), nullptr);
  EXPECT_EQ(s.as<Sphere>()->center, Vec3(1, 2, 3));
  EXPECT_EQ(s.as<Sphere>()->radius, 0.5);
  const Primitive t = clippedSolid(TorusSurface{Vec3(1, 0, 0), Vec3::UnitY(), 2.0, 0.5}, box);
  ASSERT_NE(t.as<Torus>(), nullptr);
  EXPECT_EQ(t.as<Torus>()->axis, Vec3::UnitY());
  EXPECT_EQ(t.as<Torus>()->majorRadius, 2.0);
  EXPECT_EQ(t.as<Torus>()->minorRadius, 0.5);
}

TEST(ClippedSolid, CylinderCapsAreFartherThanTheDiagonalAndTheRadius) {
  Rng rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Aabb box = randomBox(rng, 5.0);
    const CylinderSurface s{randomPointNear(rng, box), randomUnit(rng), uniform(rng, 0.1, 10)};
    const Primitive prim = clippedSolid(s, box);
    const Cylinder* cyl = prim.as<Cylinder>();
    ASSERT_NE(cyl, nullptr);
    EXPECT_EQ(cyl->axis, s.axisDir);
    EXPECT_EQ(cyl->radius, s.radius);
    // The centre is on the axis.
    EXPECT_LT(cylinderDistance(CylinderSurface{s.axisPoint, s.axisDir, 0.0}, cyl->center),
              1e-9 * 10);
    for (const Vec3& p : boxSamples(rng, box, 0)) {
      const double toCap = 0.5 * cyl->height - std::abs((p - cyl->center).dot(cyl->axis));
      EXPECT_GT(toCap, box.diagonal() + s.radius - 1e-9 * cyl->height);
    }
  }
}

// A box deep inside a wide cylinder: its points are farther from the lateral
// surface than the box's diagonal, so caps at only one diagonal would be
// nearer than the lateral surface and change the value.
TEST(ClippedSolid, BoxDeepInsideAWideCylinder) {
  Rng rng(11);
  const Aabb box{Vec3::Constant(-1), Vec3::Constant(1)};
  const CylinderSurface wide{Vec3(0.3, -0.2, 0.1), Vec3(1, 2, 2) / 3.0, 100.0};
  const auto [inside, outside] = expectExactInBox(wide, box, rng, 2000);
  EXPECT_EQ(outside, 0);
  EXPECT_GT(inside, 2000);
  // At the origin: rho^2 = |d|^2 - (d·axis)^2 with d = -axisPoint.
  const double rho = std::sqrt(0.14 - 0.01 / 9.0);
  const Primitive prim = clippedSolid(wide, box);
  EXPECT_NEAR(prim.value(Vec3::Zero()), 100.0 - rho, 1e-12);
  // Caps only one diagonal away would have been wrong here.
  Cylinder shortCyl = *prim.as<Cylinder>();
  shortCyl.height -= 2.0 * wide.radius;
  EXPECT_LT(Primitive(shortCyl).value(Vec3::Zero()), 0.5 * (100.0 - rho));
}

// Points behind the apex: outside, at their distance to the apex (the
// frustum's lateral surface near the apex gives the same value).
TEST(ClippedSolid, ConeBehindTheApexIsTheDistanceToTheApex) {
  const ConeSurface cone{Vec3(1, 1, 1), Vec3::UnitZ(), std::numbers::pi / 6};
  const Aabb box{Vec3(-3, -3, -5), Vec3(5, 5, 6)};  // contains the apex
  const Primitive prim = clippedSolid(cone, box);
  const Cone* c = prim.as<Cone>();
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->radiusBottom, 0.0);
  test::expectNear(c->center - 0.5 * c->height * c->axis, cone.apex, 1e-12);
  int behind = 0;
  Rng rng(3);
  for (const Vec3& p : boxSamples(rng, box, 20000)) {
    const Vec3 d = p - cone.apex;
    const double z = d.z(), rho = std::hypot(d.x(), d.y());
    const double a = cone.halfAngle;
    if (z * std::cos(a) + rho * std::sin(a) > 0.0) continue;
    ++behind;
    EXPECT_NEAR(prim.value(p), -d.norm(), 1e-12 * box.diagonal()) << test::str(p);
  }
  EXPECT_GT(behind, 2000);
  // Straight behind the apex on the axis, and on the apex itself.
  EXPECT_NEAR(prim.value(Vec3(1, 1, -2)), -3.0, 1e-12);
  EXPECT_NEAR(prim.value(cone.apex), 0.0, 1e-12);
  // Inside, on the axis: distance z·sin(a) to the surface.
  EXPECT_NEAR(prim.value(Vec3(1, 1, 5)), 4.0 * std::sin(cone.halfAngle), 1e-12);
}

TEST(ClippedSolid, ConeBoxFarFromTheApexAndWideAngle) {
  Rng rng(5);
  const Aabb box{Vec3(100, 100, 100), Vec3(101, 102, 103)};
  expectExactInBox(ConeSurface{Vec3::Zero(), Vec3(1, 1, 1).normalized(), 0.1}, box, rng);
  expectExactInBox(ConeSurface{Vec3(100.5, 101, 99), Vec3::UnitZ(), 1.5}, box, rng);
  expectExactInBox(ConeSurface{Vec3(100.5, 101, 101.5), -Vec3::UnitZ(), 1.2}, box, rng);
}

TEST(ClippedSolid, DegenerateBoxOfOnePoint) {
  const Aabb point{Vec3(1, 2, 3), Vec3(1, 2, 3)};
  const ConeSurface apexHere{Vec3(1, 2, 3), Vec3::UnitX(), 0.5};
  EXPECT_NEAR(clippedSolid(apexHere, point).value(Vec3(1, 2, 3)), 0.0, 1e-15);
  const CylinderSurface cyl{Vec3(1, 2, 0), Vec3::UnitZ(), 2.0};
  EXPECT_NEAR(clippedSolid(cyl, point).value(Vec3(1, 2, 3)), 2.0, 1e-15);
}

TEST(ClippedSolid, RejectsBadBoxesAndSurfaces) {
  const Aabb box{Vec3::Zero(), Vec3::Ones()};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const PlaneSurface plane{Vec3::UnitZ(), 0.0};
  EXPECT_THROW(clippedSolid(plane, Aabb{}), std::invalid_argument);
  EXPECT_THROW(clippedSolid(plane, Aabb::everything()), std::invalid_argument);
  EXPECT_THROW(clippedSolid(plane, Aabb{Vec3::Zero(), Vec3(1, inf, 1)}), std::invalid_argument);
  const std::vector<SurfaceShape> bad = {
      PlaneSurface{Vec3(0, 0, 2), 0.0},
      PlaneSurface{Vec3::UnitZ(), nan},
      PlaneSurface{Vec3::Zero(), 1.0},
      CylinderSurface{Vec3::Zero(), Vec3::UnitZ(), 0.0},
      CylinderSurface{Vec3::Zero(), Vec3::UnitZ(), -1.0},
      CylinderSurface{Vec3(nan, 0, 0), Vec3::UnitZ(), 1.0},
      CylinderSurface{Vec3::Zero(), Vec3(1, 1, 0), 1.0},
      CylinderSurface{Vec3::Zero(), Vec3::UnitZ(), inf},
      ConeSurface{Vec3::Zero(), Vec3::UnitZ(), 0.0},
      ConeSurface{Vec3::Zero(), Vec3::UnitZ(), std::numbers::pi / 2},
      ConeSurface{Vec3::Zero(), Vec3::UnitZ(), nan},
      ConeSurface{Vec3::Zero(), Vec3::Zero(), 0.5},
      ConeSurface{Vec3(0, inf, 0), Vec3::UnitZ(), 0.5},
      SphereSurface{Vec3::Zero(), 0.0},
      SphereSurface{Vec3(0, 0, nan), 1.0},
      TorusSurface{Vec3::Zero(), Vec3::UnitZ(), 1.0, 2.0},
      TorusSurface{Vec3::Zero(), Vec3::UnitZ(), 1.0, 0.0},
      TorusSurface{Vec3::Zero(), Vec3(0, 0, 0.5), 1.0, 0.25},
  };
  for (std::size_t i = 0; i < bad.size(); ++i) {
    EXPECT_THROW(clippedSolid(bad[i], box), std::invalid_argument) << "case " << i;
  }
}

}  // namespace
}  // namespace csgvox
