// Bores found from their walls: arcs of points no surface took, whose
// normals point to (or away from) one axis along a direction of the part,
// become hole (or boss) cylinders; short arcs, bores with a face inside and
// cylinders already found do not.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "io/scan_reader.h"
#include "part_list.h"
#include "pipeline/detect_and_fit.h"
#include "primitives/wall_bores.h"

namespace csgvox {
namespace {

// A plate's top face z = 0 over [-20, 20] x [-15, 15] (one plane surface,
// its points assigned), then walls of points no surface holds.
struct WallScan {
  PointCloud cloud;
  DetectionResult result;
  std::mt19937 rng{5};

  WallScan() {
    Surface top;
    top.shape = PlaneSurface{Vec3::UnitZ(), 0.0};
    top.rms = 0.01;
    for (double x = -20.0; x <= 20.0; x += 0.5) {
      for (double y = -15.0; y <= 15.0; y += 0.5) {
        top.inliers.push_back(std::uint32_t(cloud.size()));
        result.assignment.push_back(0);
        cloud.points.emplace_back(x, y, 0.0);
        cloud.normals.push_back(Vec3::UnitZ());
      }
    }
    result.surfaces.push_back(std::move(top));
  }

  // `count` points on the wall of radius r about the z axis through (cx,
  // cy), from z0 to z1, over angles [a0, a1); normals to the axis (a hole)
  // or away from it (a boss), tilted by up to `tilt` radians.
  void wall(double cx, double cy, double r, double z0, double z1, double a0, double a1, int count,
            bool hole, double tilt = 0.1) {
    std::uniform_real_distribution<double> angle(a0, a1), z(z0, z1), off(-tilt, tilt),
        noise(-0.02, 0.02);
    for (int k = 0; k < count; ++k) {
      const double a = angle(rng);
      const double rr = r + noise(rng);
      cloud.points.emplace_back(cx + rr * std::cos(a), cy + rr * std::sin(a), z(rng));
      Vec3 n(std::cos(a + off(rng)), std::sin(a + off(rng)), off(rng));
      if (hole) n = -n;
      cloud.normals.push_back(n.normalized());
      result.assignment.push_back(-1);
    }
  }

  void finish() {
    result.status = DetectionResult::Status::Ok;
    result.diagonal = cloud.diagonal();
    result.noise = 0.02;
    result.epsilon = 0.15;
    result.clusterEpsilon = 1.0;
    result.minPoints = 30;
    result.normalThreshold = 0.9;
    result.centroids.assign(result.surfaces.size(), Vec3::Zero());
  }
};

constexpr double kTurn = 2.0 * std::numbers::pi;

TEST(WallBores, AHoleAndABossSeenOnlyOnPartOfTheirWallsBecomeCylindersAlongThePartsDirection) {
  WallScan scan;
  scan.wall(-10.0, 0.0, 3.0, -5.0, 0.0, 0.3, 0.3 + 0.6 * kTurn, 60, true);  // a hole, 216 degrees
  scan.wall(10.0, 2.0, 2.5, 0.0, 4.0, 1.0, 1.0 + 0.4 * kTurn, 45, false);   // a boss, 144 degrees
  scan.finish();
  const std::size_t before = scan.result.surfaces.size();
  const WallBoreStats stats = addWallBores(scan.cloud, scan.result);
  ASSERT_EQ(stats.bores, 2u);
  ASSERT_EQ(scan.result.surfaces.size(), before + 2);
  ASSERT_EQ(scan.result.centroids.size(), scan.result.surfaces.size());
  int holes = 0, bosses = 0;
  for (std::size_t s = before; s < scan.result.surfaces.size(); ++s) {
    const Surface& surface = scan.result.surfaces[s];
    const auto* c = surface.as<CylinderSurface>();
    ASSERT_NE(c, nullptr);
    EXPECT_GT(std::abs(c->axisDir.z()), 0.9999);
    const bool hole = !surface.convex;
    (hole ? holes : bosses) += 1;
    const double cx = hole ? -10.0 : 10.0, cy = hole ? 0.0 : 2.0, r = hole ? 3.0 : 2.5;
    EXPECT_NEAR(c->axisPoint.x(), cx, 0.05);
    EXPECT_NEAR(c->axisPoint.y(), cy, 0.05);
    EXPECT_NEAR(c->radius, r, 0.05);
    EXPECT_EQ(surface.inliers.size(), hole ? 60u : 45u);
    for (std::uint32_t i : surface.inliers) EXPECT_EQ(scan.result.assignment[i], int(s));
  }
  EXPECT_EQ(holes, 1);
  EXPECT_EQ(bosses, 1);
}

TEST(WallBores, ShortArcsFewPointsAndMixedNormalsAreNoBores) {
  WallScan scan;
  scan.wall(-10.0, 0.0, 3.0, -5.0, 0.0, 0.0, 0.125 * kTurn, 80, true);  // 45 degrees only
  scan.wall(10.0, 0.0, 3.0, -5.0, 0.0, 0.0, kTurn, 20, true);           // 20 points (least 30)
  // Around one circle, half the normals face the axis and half away: no
  // side holds enough.
  scan.wall(0.0, 8.0, 3.0, -5.0, 0.0, 0.0, kTurn, 25, true);
  scan.wall(0.0, 8.0, 3.0, -5.0, 0.0, 0.0, kTurn, 25, false);
  scan.finish();
  const std::size_t before = scan.result.surfaces.size();
  const WallBoreStats stats = addWallBores(scan.cloud, scan.result);
  EXPECT_EQ(stats.bores, 0u);
  EXPECT_EQ(scan.result.surfaces.size(), before);
}

TEST(WallBores, ABoreWithAFaceInsideBetweenItsEndsOrOneAlreadyFoundIsNotAdded) {
  WallScan scan;
  // A wall from z = -6 to 0 with the points of a face across it at z = -3
  // (no bore: an arc of some other shape over a flat floor).
  scan.wall(-10.0, 0.0, 3.0, -6.0, 0.0, 0.0, kTurn, 70, true);
  for (double x = -12.0; x <= -8.0; x += 0.5) {
    for (double y = -2.0; y <= 2.0; y += 0.5) {
      scan.cloud.points.emplace_back(x, y, -3.0);
      scan.cloud.normals.push_back(Vec3::UnitZ());
      scan.result.assignment.push_back(0);
    }
  }
  // A hole whose cylinder the detection found already (its wall points
  // left unassigned beside it).
  scan.wall(10.0, 0.0, 3.0, -5.0, 0.0, 0.0, kTurn, 70, true);
  Surface found;
  found.shape = CylinderSurface{Vec3(10.0, 0.0, -2.5), Vec3::UnitZ(), 3.02};
  found.convex = false;
  scan.result.surfaces.push_back(found);
  scan.finish();
  const std::size_t before = scan.result.surfaces.size();
  const WallBoreStats stats = addWallBores(scan.cloud, scan.result);
  EXPECT_EQ(stats.bores, 0u);
  EXPECT_GE(stats.tried, 1u);
  EXPECT_EQ(scan.result.surfaces.size(), before);
}

TEST(WallBores, StripsOfTwoParallelFacesAreNoBoss) {
  // Free points of two faces z = 20 +- 5, 2 wide in x: along y
  // (a direction the part shows: a cylinder found along it elsewhere) each
  // strip lies within epsilon of the circle of radius 5 about the y axis,
  // its normals radial. Together they span the circle, but each covers
  // under 30 degrees of it: no boss.
  WallScan scan;
  for (double sign : {-1.0, 1.0}) {
    for (double x = -1.0; x <= 1.0 + 1e-9; x += 0.25) {
      for (double y = -10.0; y <= 10.0 + 1e-9; y += 0.25) {
        scan.cloud.points.emplace_back(x, y, 5.0 * sign + 20.0);
        // Normals tilted as a blend would tilt them: radial about the axis.
        scan.cloud.normals.push_back(Vec3(x, 0.0, 5.0 * sign).normalized());
        scan.result.assignment.push_back(-1);
      }
    }
  }
  Surface rod;
  rod.shape = CylinderSurface{Vec3(15.0, 0.0, 0.0), Vec3::UnitY(), 1.0};
  scan.result.surfaces.push_back(rod);
  scan.finish();
  const std::size_t before = scan.result.surfaces.size();
  const WallBoreStats stats = addWallBores(scan.cloud, scan.result);
  EXPECT_GE(stats.tried, 1u);
  EXPECT_EQ(stats.bores, 0u);
  EXPECT_EQ(scan.result.surfaces.size(), before);
}

// A groove's wall x = 5 (y in [-10, 10], z in [-3, 0]) whose points no
// surface took: a third of its normals along -x, a third blended 45
// degrees towards +z, a third 70 degrees off (the faces beside it). The
// part shows the x direction by its end face x = 20.
TEST(WallPlanes, ANarrowFaceWithBlendedNormalsBecomesAPlaneAcrossThePartsDirection) {
  WallScan scan;
  Surface end;
  end.shape = PlaneSurface{Vec3::UnitX(), 20.0};
  end.rms = 0.01;
  for (double y = -15.0; y <= 15.0; y += 1.0) {
    for (double z = -3.0; z <= 0.0; z += 1.0) {
      end.inliers.push_back(std::uint32_t(scan.cloud.size()));
      scan.result.assignment.push_back(1);
      scan.cloud.points.emplace_back(20.0, y, z);
      scan.cloud.normals.push_back(Vec3::UnitX());
    }
  }
  scan.result.surfaces.push_back(std::move(end));
  std::uniform_real_distribution<double> y(-10.0, 10.0), z(-3.0, -0.5), noise(-0.02, 0.02);
  const double tilts[] = {0.0, std::numbers::pi / 4.0, 70.0 * std::numbers::pi / 180.0};
  for (int k = 0; k < 300; ++k) {
    const double tilt = tilts[k % 3];
    scan.cloud.points.emplace_back(5.0 + noise(scan.rng), y(scan.rng), z(scan.rng));
    scan.cloud.normals.emplace_back(-std::cos(tilt), 0.0, std::sin(tilt));
    scan.result.assignment.push_back(-1);
  }
  // Points a little above the top face (0.2: beyond epsilon, within two):
  // its edge, not a face of their own.
  for (int k = 0; k < 60; ++k) {
    scan.cloud.points.emplace_back(y(scan.rng), y(scan.rng), 0.2);
    scan.cloud.normals.push_back(Vec3::UnitZ());
    scan.result.assignment.push_back(-1);
  }
  // Scattered points with random normals.
  std::uniform_real_distribution<double> any(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    scan.cloud.points.emplace_back(10.0 * any(scan.rng), 10.0 * any(scan.rng),
                                   -1.5 + 1.5 * any(scan.rng));
    scan.cloud.normals.push_back(
        Vec3(any(scan.rng), any(scan.rng), any(scan.rng)).normalized());
    scan.result.assignment.push_back(-1);
  }
  scan.finish();
  const std::size_t before = scan.result.surfaces.size();
  const WallPlaneStats stats = addWallPlanes(scan.cloud, scan.result);
  ASSERT_EQ(stats.planes, 1u);
  ASSERT_EQ(scan.result.surfaces.size(), before + 1);
  const Surface& face = scan.result.surfaces.back();
  const auto* plane = face.as<PlaneSurface>();
  ASSERT_NE(plane, nullptr);
  EXPECT_GT(plane->normal.dot(-Vec3::UnitX()), 0.9999);
  EXPECT_NEAR(plane->offset, -5.0, 0.03);
  // The blended normals' points too, not the 70-degree ones.
  EXPECT_GE(face.inliers.size(), 198u);
  EXPECT_LE(face.inliers.size(), 202u);
  for (std::uint32_t i : face.inliers) {
    EXPECT_EQ(scan.result.assignment[i], int(before));
    EXPECT_GE(-scan.cloud.normals[i].x(), 0.5);
  }
  EXPECT_EQ(scan.result.centroids.size(), scan.result.surfaces.size());

  // Fewer facing points than a surface's least support: no face.
  WallScan sparse;
  for (int k = 0; k < 40; ++k) {
    sparse.cloud.points.emplace_back(5.0, y(sparse.rng), z(sparse.rng));
    sparse.cloud.normals.emplace_back(-std::cos(tilts[k % 3]), 0.0, std::sin(tilts[k % 3]));
    sparse.result.assignment.push_back(-1);
  }
  sparse.finish();
  EXPECT_EQ(addWallPlanes(sparse.cloud, sparse.result).planes, 0u);
}

TEST(WallBores, TheSameSeedFindsTheSameBores) {
  const auto run = [](std::uint64_t seed) {
    WallScan scan;
    scan.wall(-10.0, 0.0, 3.0, -5.0, 0.0, 0.0, 0.5 * kTurn, 50, true);
    scan.wall(8.0, 5.0, 1.5, -3.0, 0.0, 0.0, kTurn, 50, true);
    scan.finish();
    WallBoreOptions options;
    options.seed = seed;
    addWallBores(scan.cloud, scan.result, options);
    return scan.result;
  };
  const DetectionResult a = run(3), b = run(3);
  ASSERT_EQ(a.surfaces.size(), 3u);  // the face and both bores
  ASSERT_EQ(a.surfaces.size(), b.surfaces.size());
  EXPECT_EQ(a.assignment, b.assignment);
  for (std::size_t s = 0; s < a.surfaces.size(); ++s) {
    const auto* ca = a.surfaces[s].as<CylinderSurface>();
    const auto* cb = b.surfaces[s].as<CylinderSurface>();
    ASSERT_EQ(ca == nullptr, cb == nullptr);
    if (ca != nullptr) {
      EXPECT_EQ(ca->radius, cb->radius);
      EXPECT_EQ(ca->axisPoint, cb->axisPoint);
    }
  }
}

TEST(WallBores, TheMainJobFindsTheHousingsCounterboresAndBoltHolesInItsScannerScan) {
  // The bundled scanner scan of housing_complex (raw x y z): its four
  // counterbores (radius 9.5) and four bolt holes (5.5) at (+-45.5, +-25.5)
  // hold 30-90 wall points each, about RANSAC's least support, and RANSAC
  // finds few of them. From their walls, every counterbore is a concave
  // cylinder along z, and three of the bolt holes (the fourth's points
  // cover 53 degrees of its wall, under the 60 asked).
  const Scan scan = readScan(test::dataDir() / "housing_complex" / "scan_scanner.ply");
  ASSERT_TRUE(scan.info.normalsEstimated);
  DetectAndFitOptions options;
  options.detect.estimatedNormals = true;
  const auto holesAt = [](const SurfacesAndCandidates& found, double radius) {
    int n = 0;
    for (double x : {-45.5, 45.5}) {
      for (double y : {-25.5, 25.5}) {
        bool hit = false;
        for (const Surface& s : found.detection.surfaces) {
          const auto* c = s.as<CylinderSurface>();
          if (c == nullptr || s.convex || std::abs(c->axisDir.z()) < 0.999) continue;
          if (std::hypot(c->axisPoint.x() - x, c->axisPoint.y() - y) < 1.0 &&
              std::abs(c->radius - radius) < 0.6) {
            hit = true;
          }
        }
        n += hit ? 1 : 0;
      }
    }
    return n;
  };
  const SurfacesAndCandidates with = detectAndFit(scan.cloud, options);
  ASSERT_TRUE(with.ok()) << with.detection.message;
  EXPECT_GE(with.wallBores.bores, 4u);
  EXPECT_NE(with.detection.message.find("found from their walls"), std::string::npos);
  EXPECT_EQ(holesAt(with, 9.5), 4);
  EXPECT_GE(holesAt(with, 5.5), 3);
  // RANSAC alone misses some. (The rims, looked for after the walls, find
  // all eight on this scan by themselves; they are left out here.)
  options.wallBores = false;
  options.rimHoles = false;
  const SurfacesAndCandidates without = detectAndFit(scan.cloud, options);
  ASSERT_TRUE(without.ok());
  EXPECT_EQ(without.wallBores.bores, 0u);
  EXPECT_LT(holesAt(without, 9.5) + holesAt(without, 5.5), 8);
}

}  // namespace
}  // namespace csgvox
