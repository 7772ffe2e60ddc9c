// Tests for primitives/normal_estimation.h on degenerate input: copies of a
// point, a scan at one position, points on a line; and determinism across
// thread counts; how far given normals agree with the surface. (Accuracy on
// spheres, boxes, tubes and the bundled scans, and the agreement of the
// bundled scans' normals, are tested with the scan reader.)

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/nearest_neighbors.h"
#include "io/scan_reader.h"
#include "mesh/surface_sampler.h"
#include "primitives/normal_estimation.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

// The bundled flange scan, with its normals (the truth here).
const PointCloud& flange() {
  static const PointCloud cloud = readScan(fs::path(CSGVOX_DATA_DIR) / "flange" / "scan.ply").cloud;
  return cloud;
}

// Fraction of estimated normals within 30 degrees of the true ones.
double agreeingFraction(const std::vector<Vec3>& estimated, const std::vector<Vec3>& truth) {
  std::size_t good = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) good += estimated[i].dot(truth[i]) > 0.866;
  return double(good) / double(truth.size());
}

// The message of the std::invalid_argument that estimateNormals throws.
std::string errorOf(PointCloud cloud, int neighbors) {
  try {
    estimateNormals(cloud, neighbors);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(EstimateNormals, ScanAtOnePositionIsRejectedWithOneLine) {
  // 200 copies of one point: the jet fit of such a neighbourhood used to
  // crash in the SVD.
  const PointCloud cloud{std::vector<Vec3>(200, Vec3(1.0, 2.0, 3.0)), {}};
  const std::string message = errorOf(cloud, 18);
  EXPECT_NE(message.find("all 200 points are at the same position"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
}

TEST(EstimateNormals, TooFewDistinctPositionsAreRejected) {
  // 100 points, but only 10 positions: fewer than 18 neighbours exist.
  std::vector<Vec3> points;
  for (int copy = 0; copy < 10; ++copy) {
    for (int i = 0; i < 10; ++i) points.push_back(flange().points[std::size_t(i)]);
  }
  const std::string message = errorOf(PointCloud{points, {}}, 18);
  EXPECT_NE(message.find("10 distinct positions among 100 points"), std::string::npos) << message;
}

TEST(EstimateNormals, PointsOnALineAreRejected) {
  std::vector<Vec3> points;
  for (int i = 0; i < 100; ++i) points.push_back(Vec3(1.0, 2.0, 3.0) + 0.01 * i * Vec3(1, 1, 0));
  const std::string message = errorOf(PointCloud{points, {}}, 18);
  EXPECT_NE(message.find("line"), std::string::npos) << message;
}

TEST(EstimateNormals, CopiesOfAPointInARealScanShareItsNormal) {
  // The flange scan with its first point repeated (18 copies used to crash)
  // and a point in the middle repeated: the copies change nothing.
  PointCloud plain{flange().points, {}};
  estimateNormals(plain, 18);
  EXPECT_GT(agreeingFraction(plain.normals, flange().normals), 0.95);
  for (std::size_t copies : {18, 19, 40, 300}) {
    SCOPED_TRACE(copies);
    PointCloud repeated{flange().points, {}};
    repeated.points.insert(repeated.points.begin() + 5000, copies, flange().points[5000]);
    repeated.points.insert(repeated.points.end(), copies, flange().points[0]);
    estimateNormals(repeated, 18);
    ASSERT_EQ(repeated.normals.size(), repeated.points.size());
    for (std::size_t i = 0; i < repeated.size(); ++i) {
      // Index of the point in the plain scan.
      const std::size_t original = i < 5000                       ? i
                                   : i < 5000 + copies            ? 5000
                                   : i < flange().size() + copies ? i - copies
                                                                  : 0;
      ASSERT_EQ(repeated.normals[i], plain.normals[original]) << "point " << i;
    }
  }
}

TEST(EstimateNormals, SameNormalsWithAnyThreadCount) {
  PointCloud parallel{flange().points, {}};
  estimateNormals(parallel, 18);
  PointCloud serial{flange().points, {}};
  {
    const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    estimateNormals(serial, 18);
  }
  EXPECT_EQ(parallel.normals, serial.normals);
}

TEST(NormalAgreement, TellsTheSurfacesNormalsFromRandomOnes) {
  std::mt19937_64 rng(9);
  std::normal_distribution<double> gauss;
  const auto randomUnit = [&]() { return Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized(); };
  EXPECT_GT(normalAgreement(flange(), 18), 0.99);
  // Turned by up to 17 degrees, as a scanner's normals may be: most still
  // agree; in random directions, about one in eight (1 - cos 30 deg).
  PointCloud tilted = flange();
  for (Vec3& n : tilted.normals) n = (n + 0.3 * randomUnit()).normalized();
  EXPECT_GT(normalAgreement(tilted, 18), 0.9);
  PointCloud random = flange();
  for (Vec3& n : random.normals) n = randomUnit();
  EXPECT_NEAR(normalAgreement(random, 18), 0.134, 0.03);
  // Flipped normals agree as well (the sign is not judged).
  PointCloud flipped = flange();
  for (Vec3& n : flipped.normals) n = -n;
  EXPECT_EQ(normalAgreement(flipped, 18), normalAgreement(flange(), 18));
  EXPECT_THROW(normalAgreement(PointCloud{flange().points, {}}, 18), std::invalid_argument);
  EXPECT_THROW(normalAgreement(flange(), 2), std::invalid_argument);
}

// Near an edge a jet fit blends the faces; on a wall narrower than the
// neighbourhood every point is near an edge. The walls' normals must still
// be the walls' own: the jet-blended ones were a few degrees off (22 % within
// 3 degrees), and RANSAC then explained the walls by wide cylinders.
TEST(EstimateNormals, NarrowWallsKeepTheirFacesNormals) {
  SampleOptions so;
  so.points = 50000;
  PointCloud cloud = sampleSurface(test::thinPlateWithTurnedHoles(), so).cloud;
  const std::vector<Vec3> truth = cloud.normals;
  estimateNormals(cloud, 18);
  const double cos3 = std::cos(3.0 * std::numbers::pi / 180.0);
  std::size_t walls = 0, right = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (std::abs(truth[i].z()) > 0.1) continue;  // the plate's faces
    ++walls;
    right += std::abs(cloud.normals[i].dot(truth[i])) >= cos3;
  }
  ASSERT_GT(walls, 3000u);
  EXPECT_GE(double(right) / double(walls), 0.8) << right << " of " << walls;
}

// jetNormal reproduces CGAL's general jet fitting (generalJetNormal) to
// rounding, sign included, on the neighbourhoods estimateNormals fits: a raw
// scanner scan's (noise, mixed pixels, outliers), of 7 to 64 points.
TEST(JetNormal, MatchesCgalsGeneralFittingOnARawScan) {
  ReadOptions raw;
  raw.removeOutliers = false;
  const std::vector<Vec3> points =
      readScan(fs::path(CSGVOX_DATA_DIR) / "knob" / "scan_scanner.ply", raw).cloud.points;
  ASSERT_GT(points.size(), 10000u);
  const NearestNeighbors nn(points);
  std::vector<std::uint32_t> hood;
  double worst = 0.0;
  std::size_t compared = 0;
  for (std::size_t i = 0; i < points.size(); i += 37) {
    for (std::size_t k : {7, 19, 40, 64}) {
      nn.kNearest(points[i], k, hood);
      const Vec3 fast = jetNormal(points, hood);
      const Vec3 general = generalJetNormal(points, hood);
      ASSERT_TRUE(general.allFinite()) << "point " << i << ", " << k << " neighbours";
      worst = std::max(worst, (fast - general).norm());
      ++compared;
    }
  }
  EXPECT_GT(compared, 1000u);
  EXPECT_LT(worst, 1e-9) << "largest difference over " << compared << " neighbourhoods";
}

// Where the quadric is not determined (five distinct points, each twice:
// rank 5 for 6 coefficients), both take the least-norm solution; more than
// 64 points take CGAL's fitting; points on a line get none; fewer than 6
// are refused.
TEST(JetNormal, RankDeficientLargeAndTooSmallNeighbourhoods) {
  const std::vector<Vec3> points{Vec3(0.0, 0.0, 0.0), Vec3(1.0, 0.1, 0.05), Vec3(0.2, 1.0, -0.03),
                                 Vec3(-0.9, 0.3, 0.08), Vec3(0.4, -1.1, 0.02)};
  const std::vector<std::uint32_t> twice{0, 1, 2, 3, 4, 0, 1, 2, 3, 4};
  const Vec3 fast = jetNormal(points, twice);
  ASSERT_TRUE(fast.allFinite());
  EXPECT_NEAR(fast.norm(), 1.0, 1e-12);
  EXPECT_LT((fast - generalJetNormal(points, twice)).norm(), 1e-9) << fast.transpose();

  // A cap of a sphere of radius 2: the normal at its pole is radial.
  std::vector<Vec3> cap{Vec3(0.0, 0.0, 2.0)};
  for (int a = 0; a < 10; ++a) {
    for (int b = 1; b <= 8; ++b) {
      const double phi = 0.02 * b, theta = 2.0 * std::numbers::pi * (a + 0.1 * b) / 10.0;
      cap.emplace_back(2.0 * std::sin(phi) * std::cos(theta), 2.0 * std::sin(phi) * std::sin(theta),
                       2.0 * std::cos(phi));
    }
  }
  std::vector<std::uint32_t> all(cap.size());
  std::iota(all.begin(), all.end(), 0u);
  ASSERT_GT(all.size(), 64u);
  EXPECT_GT(std::abs(jetNormal(cap, all).z()), 1.0 - 1e-9);
  EXPECT_EQ(jetNormal(cap, all), generalJetNormal(cap, all));

  // Points on a line (up to rounding) span no surface: no normal.
  std::vector<Vec3> line;
  for (int s = 0; s < 12; ++s) line.push_back(Vec3(100.0, -50.0, 20.0) + 0.1 * s * Vec3(1.0, 2.0, 3.0));
  std::vector<std::uint32_t> along(line.size());
  std::iota(along.begin(), along.end(), 0u);
  EXPECT_EQ(jetNormal(line, along), Vec3::Zero());

  const std::vector<std::uint32_t> five{0, 1, 2, 3, 4};
  EXPECT_THROW(jetNormal(cap, five), std::invalid_argument);
  EXPECT_THROW(generalJetNormal(cap, five), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
