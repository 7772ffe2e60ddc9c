// The scanner model (scanner/scanner.h) and its casters (scanner/tree_caster.h,
// scanner/mesh_caster.h): exact hits, unseen table face, incidence cutoff,
// artifact counts, determinism, exact point counts, mesh against tree, and
// the registration error.

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "core/csg_tree.h"
#include "mesh/mesh_export.h"
#include "scanner/mesh_caster.h"
#include "scanner/scanner.h"
#include "scanner/tree_caster.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

// A block with a through hole: flat faces, a bore, a table face at z = 0.
CsgTree blockWithHole() {
  Box box;
  box.center = Vec3(0, 0, 1);
  box.halfSize = Vec3(2, 1.5, 1);
  Cylinder hole;
  hole.center = Vec3(0.5, 0, 1);
  hole.radius = 0.5;
  hole.height = 3;
  return CsgTree::subtract({CsgTree::leaf(box), CsgTree::leaf(hole)});
}

// Every primitive kind at once: a box minus a cylinder, a cone, a torus, and
// a sphere cut by a half-space.
CsgTree everyKind() {
  Cone cone;
  cone.center = Vec3(-1.2, 0, 2.5);
  cone.radiusBottom = 0.7;
  cone.radiusTop = 0.2;
  cone.height = 1.0;
  Torus torus;
  torus.center = Vec3(1.2, 0, 2.25);
  torus.majorRadius = 0.6;
  torus.minorRadius = 0.25;
  Sphere sphere;
  sphere.center = Vec3(0, 0, 2.0);
  sphere.radius = 0.6;
  HalfSpace cut;
  cut.normal = Vec3(0, 1, 1).normalized();
  cut.offset = cut.normal.dot(Vec3(0, 0, 2.2));
  return CsgTree::unite({blockWithHole(), CsgTree::leaf(cone), CsgTree::leaf(torus),
                         CsgTree::intersect({CsgTree::leaf(sphere), CsgTree::leaf(cut)})});
}

// No noise, no artifacts: every point is a pixel's exact hit.
ScannerOptions exactOptions() {
  ScannerOptions o;
  o.depthNoise = 0.0;
  o.mixedPixels = 0.0;
  o.outliers = 0.0;
  o.registrationTranslation = 0.0;
  o.registrationRotation = 0.0;
  o.points = 4000;
  return o;
}

Vec3 outwardNormal(const CsgTree& tree, const Vec3& p) {
  return -tree.evaluate(p).gradient.normalized();
}

bool sameCloud(const ScannerScan& a, const ScannerScan& b) {
  return a.cloud.points == b.cloud.points && a.cloud.normals == b.cloud.normals &&
         a.kinds == b.kinds && a.sensorOf == b.sensorOf;
}

TEST(TreeCaster, HitsEveryPrimitiveKindAtItsFirstCrossing) {
  std::mt19937_64 rng(5);
  for (PrimitiveType type : test::allPrimitiveTypes()) {
    if (type == PrimitiveType::HalfSpace) continue;  // unbounded: cut by a sphere below
    const Primitive prim = test::randomPrimitive(type, rng);
    const CsgTree tree = CsgTree::leaf(prim);
    const TreeCaster caster(tree);
    const Aabb box = caster.bounds();
    const double d = box.diagonal();
    int hits = 0;
    for (int i = 0; i < 300; ++i) {
      const Vec3 origin = box.center() + 1.5 * d * test::randomUnit(rng);
      const Vec3 target = test::randomPoint(rng, box);
      const Vec3 dir = (target - origin).normalized();
      const auto hit = caster.firstHit(origin, dir, 10 * d);
      if (!hit) continue;
      ++hits;
      const Vec3 p = origin + hit->distance * dir;
      EXPECT_LT(std::abs(prim.value(p)), 1e-8 * d) << primitiveTypeName(type);
      // Nothing of the solid before the hit.
      for (int k = 0; k < 200; ++k) {
        const double t = hit->distance * (k + 0.5) / 200.0 * (1.0 - 1e-6);
        ASSERT_LT(prim.value(origin + t * dir), 0.0) << primitiveTypeName(type);
      }
      EXPECT_GT(hit->normal.dot(-dir), -1e-9) << primitiveTypeName(type);
    }
    EXPECT_GT(hits, 30) << primitiveTypeName(type);
  }
}

TEST(Scanner, ExactScanLiesOnTheSurfaceWithNormalsOfTheRightSign) {
  const CsgTree tree = everyKind();
  const TreeCaster caster(tree);
  ScannerOptions o = exactOptions();
  o.normals = ScannerNormals::Scanner;
  const ScannerScan s = scanPart(caster, o);
  ASSERT_EQ(s.cloud.size(), o.points);
  ASSERT_TRUE(s.cloud.hasNormals());
  std::size_t agree = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Vec3& p = s.cloud.points[i];
    ASSERT_LT(std::abs(tree.value(p)), 1e-7 * s.diagonal) << test::str(p);
    EXPECT_NEAR(s.cloud.normals[i].norm(), 1.0, 1e-9);
    agree += s.cloud.normals[i].dot(outwardNormal(tree, p)) > 0.0;
    // Facing the sensor.
    EXPECT_GT(s.cloud.normals[i].dot(s.sensors[s.sensorOf[i]] - p), 0.0);
  }
  EXPECT_GE(double(agree), 0.98 * double(s.cloud.size()));
}

TEST(Scanner, OneSetupLeavesTheTableFaceUnseenTwoSetupsSeeIt) {
  const CsgTree tree = blockWithHole();
  const TreeCaster caster(tree);
  const double zTable = tree.bounds().min.z();
  const auto onTable = [&](const ScannerScan& s) {
    std::size_t n = 0;
    for (const Vec3& p : s.cloud.points) n += p.z() < zTable + 1e-6;
    return n;
  };
  ScannerOptions o = exactOptions();
  o.setups = 1;
  const ScannerScan one = scanPart(caster, o);
  EXPECT_EQ(onTable(one), 0u);
  o.setups = 2;
  const ScannerScan two = scanPart(caster, o);
  EXPECT_GT(onTable(two), 100u);
  // The bottom points all come from setup 2.
  for (std::size_t i = 0; i < two.cloud.size(); ++i) {
    if (two.cloud.points[i].z() < zTable + 1e-6) {
      EXPECT_EQ(two.setupOf(two.sensorOf[i]), 1);
    }
  }
  EXPECT_EQ(two.sensors.size(), 2u * 8u * 2u);
}

TEST(Scanner, IncidenceCutoffIsRespected) {
  const CsgTree tree = everyKind();
  const TreeCaster caster(tree);
  for (double limit : {40.0, 75.0}) {
    ScannerOptions o = exactOptions();
    o.maxIncidence = limit;
    const ScannerScan s = scanPart(caster, o);
    EXPECT_GT(s.counts.droppedIncidence, 0u);
    double worst = 0.0;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      const Vec3& p = s.cloud.points[i];
      const Vec3 toSensor = (s.sensors[s.sensorOf[i]] - p).normalized();
      const double c = std::clamp(toSensor.dot(outwardNormal(tree, p)), -1.0, 1.0);
      worst = std::max(worst, std::acos(c) * 180.0 / std::numbers::pi);
    }
    // Edges: the gradient picks one face; a hit exactly on an edge may be
    // judged by the other. Allow a sliver of them.
    EXPECT_LT(worst, limit + 1e-6) << limit;
  }
}

TEST(Scanner, ArtifactCountsFollowTheOptions) {
  const CsgTree tree = blockWithHole();
  const TreeCaster caster(tree);
  ScannerOptions o = exactOptions();
  o.points = 0;  // every point
  o.resolution = 64;
  o.outliers = 0.01;
  for (double probability : {0.0, 0.5, 1.0}) {
    o.mixedPixels = probability;
    const ScannerScan s = scanPart(caster, o);
    const auto count = [&](ScanPointKind kind) {
      return std::size_t(std::count(s.kinds.begin(), s.kinds.end(), kind));
    };
    EXPECT_EQ(count(ScanPointKind::Outlier), s.counts.outliers);
    EXPECT_EQ(count(ScanPointKind::Mixed), s.counts.mixed);
    EXPECT_EQ(s.counts.points, s.counts.hits - s.counts.droppedIncidence + s.counts.outliers);
    EXPECT_EQ(s.cloud.size(), s.counts.points);
    EXPECT_EQ(s.counts.rays, 32u * 64u * 64u);
    // Outliers: the fraction of each view's points, rounded per view.
    const double pixelPoints = double(s.counts.hits - s.counts.droppedIncidence);
    EXPECT_NEAR(double(s.counts.outliers), 0.01 * pixelPoints, 0.5 * double(s.sensors.size()));
    // Mixed pixels: each edge pixel with the probability.
    ASSERT_GT(s.counts.edgePixels, 100u);
    const double n = double(s.counts.edgePixels);
    const double sd = std::sqrt(n * probability * (1.0 - probability));
    EXPECT_NEAR(double(s.counts.mixed), probability * n, 4.0 * sd + 0.5) << probability;
    // Outliers lie within the grown box.
    const Aabb grown = tree.bounds().grown(o.outlierMargin * s.diagonal + 1e-9);
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      if (s.kinds[i] == ScanPointKind::Outlier) {
        EXPECT_TRUE(grown.contains(s.cloud.points[i]));
      }
    }
  }
}

TEST(Scanner, MixedPointsLieBetweenTheTwoDepths) {
  const CsgTree tree = blockWithHole();
  const TreeCaster caster(tree);
  ScannerOptions o = exactOptions();
  o.mixedPixels = 1.0;
  o.points = 0;
  o.resolution = 48;
  const ScannerScan s = scanPart(caster, o);
  std::size_t offSurface = 0, mixed = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const double f = std::abs(tree.value(s.cloud.points[i]));
    if (s.kinds[i] == ScanPointKind::Mixed) {
      ++mixed;
      offSurface += f > 1e-3 * s.diagonal;
    } else {
      EXPECT_LT(f, 1e-7 * s.diagonal);
    }
  }
  ASSERT_GT(mixed, 0u);
  EXPECT_GT(double(offSurface), 0.5 * double(mixed));
}

TEST(Scanner, DepthNoiseHasTheModelledSigma) {
  // A box: the distance to a face is the depth error times cos(incidence).
  Box box;
  box.center = Vec3(0, 0, 1);
  box.halfSize = Vec3(1.5, 1, 1);
  const CsgTree tree = CsgTree::leaf(box);
  const TreeCaster caster(tree);
  ScannerOptions o = exactOptions();
  o.setups = 1;
  o.depthNoise = 0.001;
  o.points = 0;
  o.resolution = 48;
  const ScannerScan s = scanPart(caster, o);
  const ScannerScan exact = [&] {
    ScannerOptions e = o;
    e.depthNoise = 0.0;
    return scanPart(caster, e);
  }();
  ASSERT_EQ(exact.cloud.size(), s.cloud.size());
  const double range = (s.sensors[0] - tree.bounds().center()).norm();
  double sum = 0.0, sum2 = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Vec3& p = exact.cloud.points[i];
    const Vec3 ray = (p - s.sensors[s.sensorOf[i]]);
    const double c = -ray.normalized().dot(outwardNormal(tree, p));
    if (c < 0.3) continue;  // near an edge the face is ambiguous
    const double ratio = ray.norm() / range;
    const double sigma = o.depthNoise * s.diagonal * ratio * ratio / c;
    const double z = (s.cloud.points[i] - p).dot(ray.normalized()) / sigma;
    sum += z;
    sum2 += z * z;
    ++n;
  }
  ASSERT_GT(n, 1000u);
  const double mean = sum / double(n);
  EXPECT_NEAR(mean, 0.0, 0.1);
  EXPECT_NEAR(std::sqrt(sum2 / double(n) - mean * mean), 1.0, 0.08);
}

TEST(Scanner, SameSeedSameCloudOnAnyNumberOfThreads) {
  const CsgTree tree = everyKind();
  const TreeCaster caster(tree);
  ScannerOptions o;
  o.points = 3000;
  o.normals = ScannerNormals::Scanner;
  const ScannerScan a = scanPart(caster, o);
  ScannerScan b, c;
  tbb::task_arena(1).execute([&] { b = scanPart(caster, o); });
  tbb::task_arena(2).execute([&] { c = scanPart(caster, o); });
  EXPECT_TRUE(sameCloud(a, b));
  EXPECT_TRUE(sameCloud(a, c));
  o.seed = 2;
  const ScannerScan d = scanPart(caster, o);
  EXPECT_FALSE(sameCloud(a, d));
}

TEST(Scanner, PointsGivesExactlyThatMany) {
  const CsgTree tree = blockWithHole();
  const TreeCaster caster(tree);
  for (std::size_t n : {500u, 7777u, 30000u}) {
    ScannerOptions o;
    o.points = n;
    const ScannerScan s = scanPart(caster, o);
    EXPECT_EQ(s.cloud.size(), n);
    EXPECT_EQ(s.kinds.size(), n);
    EXPECT_EQ(s.sensorOf.size(), n);
    EXPECT_EQ(s.counts.kept, n);
    EXPECT_GE(s.counts.points, n);
    EXPECT_FALSE(s.cloud.hasNormals());
  }
  // A fixed resolution too small for the points asked for is refused.
  ScannerOptions o;
  o.resolution = 8;
  o.points = 100000;
  EXPECT_THROW(scanPart(caster, o), std::invalid_argument);
}

TEST(Scanner, DensityVariationRampsTheDensityAlongTheLongestSide) {
  // The block's longest side is x (4 long): a ramp of F = 10 keeps points at
  // the low-x end with weight about 10^-0.05 and at the high-x end about
  // 10^-0.95, so the ends' density ratio grows by about 7.9 over the even scan.
  const CsgTree tree = blockWithHole();
  const TreeCaster caster(tree);
  const auto endRatio = [&](double variation) {
    ScannerOptions o;
    o.points = 20000;
    o.outliers = 0.0;
    o.mixedPixels = 0.0;
    o.densityVariation = variation;
    const ScannerScan s = scanPart(caster, o);
    EXPECT_EQ(s.cloud.size(), 20000u);
    double low = 0, high = 0;
    for (const Vec3& p : s.cloud.points) {
      low += p.x() < -1.6;
      high += p.x() > 1.6;
    }
    return low / std::max(high, 1.0);
  };
  const double even = endRatio(1.0);
  const double ramped = endRatio(10.0);
  EXPECT_GT(even, 0.7);
  EXPECT_LT(even, 1.4);
  EXPECT_GT(ramped / even, 6.0);
  EXPECT_LT(ramped / even, 10.0);
}

TEST(Scanner, TreeAndMeshCastersAgree) {
  // A box by hand (exact), and a cylinder through the project's mesher.
  Box box;
  box.center = Vec3(0, 0, 0.5);
  box.halfSize = Vec3(1, 0.75, 0.5);
  TriangleMesh boxMesh;
  for (int k = 0; k < 8; ++k) {
    boxMesh.vertices.push_back(box.center + Vec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1)
                                                .cwiseProduct(box.halfSize));
  }
  // Counter-clockwise seen from outside.
  boxMesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  ASSERT_TRUE(boxMesh.isClosed());
  ASSERT_GT(boxMesh.volume(), 0.0);
  Cylinder cyl;
  cyl.center = Vec3(0, 0, 0.6);
  cyl.radius = 0.5;
  cyl.height = 1.2;
  MeshOptions mo;
  mo.resolution = 96;
  const TriangleMesh cylMesh = meshTree(CsgTree::leaf(cyl), mo);

  struct Case {
    CsgTree tree;
    const TriangleMesh* mesh;
    double tolerance;  // fraction of D
  };
  for (const Case& c : {Case{CsgTree::leaf(box), &boxMesh, 1e-9},
                        Case{CsgTree::leaf(cyl), &cylMesh, 2e-3}}) {
    const TreeCaster treeCaster(c.tree);
    const MeshCaster meshCaster(*c.mesh);
    const double d = treeCaster.bounds().diagonal();
    // The same rays at both.
    std::mt19937_64 rng(3);
    int both = 0, disagree = 0;
    for (int i = 0; i < 2000; ++i) {
      const Vec3 origin = treeCaster.bounds().center() + 2.0 * d * test::randomUnit(rng);
      const Vec3 dir = (test::randomPoint(rng, treeCaster.bounds()) - origin).normalized();
      const auto a = treeCaster.firstHit(origin, dir, 10 * d);
      const auto b = meshCaster.firstHit(origin, dir, 10 * d);
      if (a.has_value() != b.has_value()) {
        ++disagree;  // a silhouette ray: the mesh's rim differs from the tree's
        continue;
      }
      if (!a) continue;
      ++both;
      EXPECT_NEAR(a->distance, b->distance, c.tolerance * d + 1e-12);
    }
    EXPECT_GT(both, 1000);
    EXPECT_LT(disagree, 40);
    // A scan of the mesh lies on the tree's surface within the mesh's tolerance.
    ScannerOptions o = exactOptions();
    const ScannerScan s = scanPart(meshCaster, o);
    ASSERT_EQ(s.cloud.size(), o.points);
    for (const Vec3& p : s.cloud.points) {
      ASSERT_LT(std::abs(c.tree.value(p)), c.tolerance * d + 1e-12);
    }
  }
}

TEST(Scanner, MisregistrationMovesSetupTwoByTheRequestedAmount) {
  const CsgTree tree = everyKind();
  const TreeCaster caster(tree);
  ScannerOptions o = exactOptions();
  o.registrationTranslation = 0.01;
  o.registrationRotation = 0.004;
  const ScannerScan s = scanPart(caster, o);
  ASSERT_EQ(s.registration.size(), 2u);
  EXPECT_TRUE(s.registration[0].isApprox(Eigen::Isometry3d::Identity()));
  const double d = s.diagonal;
  const Vec3 centre = tree.bounds().center();
  std::size_t second = 0;
  double sum = 0.0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Vec3& p = s.cloud.points[i];
    if (s.setupOf(s.sensorOf[i]) == 0) {
      EXPECT_LT(std::abs(tree.value(p)), 1e-7 * d);
      continue;
    }
    ++second;
    const Vec3 exact = s.registration[1].inverse() * p;
    EXPECT_LT(std::abs(tree.value(exact)), 1e-7 * d);
    const double moved = (p - exact).norm();
    const double turn = o.registrationRotation * (exact - centre).norm();
    EXPECT_GE(moved, o.registrationTranslation * d - turn - 1e-9);
    EXPECT_LE(moved, o.registrationTranslation * d + turn + 1e-9);
    sum += moved;
  }
  ASSERT_GT(second, 1000u);
  EXPECT_NEAR(sum / double(second), o.registrationTranslation * d,
              0.5 * o.registrationRotation * d);
  // The registration is a rigid motion of the requested size.
  const Eigen::AngleAxisd turn(s.registration[1].linear());
  EXPECT_NEAR(turn.angle(), o.registrationRotation, 1e-9);
}

TEST(Scanner, BadOptionsAreRefusedNamingTheOption) {
  const TreeCaster caster(blockWithHole());
  const auto message = [&](const ScannerOptions& o) {
    try {
      scanPart(caster, o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  ScannerOptions o;
  o.elevations = {20, 95};
  EXPECT_NE(message(o).find("elevation 95"), std::string::npos) << message(o);
  o = {};
  o.setups = 3;
  EXPECT_NE(message(o).find("setups"), std::string::npos);
  o = {};
  o.maxIncidence = 0;
  EXPECT_NE(message(o).find("max incidence"), std::string::npos);
  o = {};
  o.densityVariation = 0.5;
  EXPECT_NE(message(o).find("density variation"), std::string::npos);
  o = {};
  o.views = 0;
  EXPECT_NE(message(o).find("views"), std::string::npos);
  EXPECT_THROW(TreeCaster(CsgTree::leaf(HalfSpace{})), std::invalid_argument);
  EXPECT_THROW(MeshCaster(TriangleMesh{}), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
