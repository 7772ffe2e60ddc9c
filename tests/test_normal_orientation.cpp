// Tests for primitives/normal_orientation.h through estimateNormals, on
// scanner-like raw scans (tests/raw_scan.h): the face the part stood on
// unseen, noise, a doubled surface, a region ten times sparser; on thin
// walls; and determinism across thread counts.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <vector>

#include "core/nearest_neighbors.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "primitives/normal_estimation.h"
#include "primitives/normal_orientation.h"
#include "raw_scan.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

// The surface points of a raw scan (no outliers), without normals.
PointCloud surfaceOf(const test::RawScan& raw, std::vector<Vec3>& truth) {
  PointCloud cloud;
  for (std::size_t i = 0; i < raw.points.size(); ++i) {
    if (raw.kind[i] != 0) continue;
    cloud.points.push_back(raw.points[i]);
    truth.push_back(raw.normals[i]);
  }
  return cloud;
}

// estimateNormals with at most `threads` worker threads.
void estimateOnThreads(PointCloud& cloud, int threads) {
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  estimateNormals(cloud, 18);
}

double signAgreement(const std::vector<Vec3>& estimated, const std::vector<Vec3>& truth) {
  std::size_t same = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) same += estimated[i].dot(truth[i]) > 0.0;
  return double(same) / double(truth.size());
}

TEST(OrientNormals, RawScansWithAnUnseenFaceNoiseAndADoubledSurfaceFaceOutwards) {
  for (const char* part : {"stepped_shaft", "flange"}) {
    for (std::uint64_t seed : {1, 2}) {
      SCOPED_TRACE(std::string(part) + " seed " + std::to_string(seed));
      test::RawScanOptions o;
      o.seed = seed;
      std::vector<Vec3> truth;
      PointCloud cloud = surfaceOf(test::makeRawScan(part, o), truth);
      estimateNormals(cloud, 18);
      // Measured: 0.983 to 0.996 (0.987 to 0.996 before edge points took
      // their face's plane, dominantPlane in normal_estimation.cpp); the
      // spanning forest alone gave 0.965 on the stepped shaft (caps turned
      // inwards).
      EXPECT_GE(signAgreement(cloud.normals, truth), 0.98);
    }
  }
}

TEST(OrientNormals, ThinWallsFaceOutwards) {
  // A 1.5 mm sheet and a 2 mm pin, 20 000 points (spacing about 1 mm).
  // Not yet: thin/slotted_plate (a 0.6 mm cut) reads 0.973, and the clean
  // thin/thin_tray (1 mm walls, every neighbourhood reaching both faces):
  // its normals' mean cosine with the true ones is 0.61 (0.07 before its
  // walls' faces were kept apart, see below), but the jet fits over both
  // faces tilt the normals themselves (12 % within 10 degrees).
  for (const char* part : {"thin/sheet_bracket", "thin/pin_base"}) {
    SCOPED_TRACE(part);
    const Scan scan = readScan(fs::path(CSGVOX_DATA_DIR) / part / "scan.ply");
    PointCloud cloud{scan.cloud.points, {}};
    estimateNormals(cloud, 18);
    EXPECT_GE(signAgreement(cloud.normals, scan.cloud.normals), 0.99);
  }
}

TEST(OrientNormals, ThinWallsOfScannerScansFaceOutwards) {
  // The bundled scanner scans (raw x y z, two setups, noise growing at
  // grazing incidence) of the tray (1 mm walls, about one point spacing
  // thick) and the sheet bracket (1.5 mm sheet): the rims between their
  // walls' faces are narrower than a neighbourhood. Measured 0.983 and
  // 0.996; before patches were kept to one face of a wall, 0.74 and 0.78
  // (the faces seen less took the other faces' side across the rims, and
  // neighbourhoods spanning both faces made the noise level so large that
  // the faces' points joined one patch).
  struct Case {
    const char* part;
    double least;
  };
  for (const Case c : {Case{"thin_tray", 0.96}, Case{"sheet_bracket", 0.98}}) {
    SCOPED_TRACE(c.part);
    const fs::path dir = fs::path(CSGVOX_DATA_DIR) / "thin" / c.part;
    const Scan scan = readScan(dir / "scan_scanner.ply");
    ASSERT_TRUE(scan.info.normalsEstimated);
    const CsgTree tree = readTreeJson(dir / "tree.json");
    std::vector<Vec3> truth;
    for (const Vec3& p : scan.cloud.points) {
      truth.push_back(-tree.evaluate(p).gradient.normalized());
    }
    const double agreement = signAgreement(scan.cloud.normals, truth);
    std::printf("%s scanner scan: %.4f of the normals outward\n", c.part, agreement);
    EXPECT_GE(agreement, c.least);
  }
}

TEST(OrientNormals, UndecidedPatchesTakeTheirDecidedNeighboursSide) {
  // The bearing housing's scanner scan: its spherical seat, deep in the
  // bore, falls into a dozen patches that each see little of the outside,
  // so half of them vote too weakly to decide. Measured 0.9895 of the
  // normals outward, and 0.94 of the seat's; 0.966 and 0.60 when undecided
  // patches kept the spanning forest's signs.
  const fs::path dir = fs::path(CSGVOX_DATA_DIR) / "bearing_housing";
  const Scan scan = readScan(dir / "scan_scanner.ply");
  ASSERT_TRUE(scan.info.normalsEstimated);
  const CsgTree tree = readTreeJson(dir / "tree.json");
  std::size_t seat = 0, seatOutward = 0, outward = 0;
  for (std::size_t i = 0; i < scan.cloud.points.size(); ++i) {
    const Vec3& p = scan.cloud.points[i];
    const bool out = scan.cloud.normals[i].dot(-tree.evaluate(p).gradient) > 0.0;
    outward += out;
    // The seat: the sphere of radius 24 about (0, 0, 26), above the flange.
    if (std::abs((p - Vec3(0, 0, 26)).norm() - 24.0) < 0.5 && p.z() > 14.0) {
      ++seat;
      seatOutward += out;
    }
  }
  const double all = double(outward) / double(scan.cloud.points.size());
  const double seatShare = double(seatOutward) / double(seat);
  std::printf("bearing housing scanner scan: %.4f of the normals outward, %.4f of the seat's\n",
              all, seatShare);
  EXPECT_GT(seat, 1000u);
  EXPECT_GE(all, 0.985);
  EXPECT_GE(seatShare, 0.9);
}

TEST(OrientNormals, ThinWalledHousingSeenThroughItsEndsFacesOutwards) {
  // InverseCSG 150, a sheet-metal housing (walls 0.15 thick, 1.9 point
  // spacings) open at both ends, as the scanner model scans it: its inner
  // faces, seen through the ends at grazing angles, hold fewer points than
  // the outer ones, so an inner point's neighbourhood reaches the outer
  // face, often with more points than its own. The jets fitted over both
  // faces turned the inner normals by up to 90 degrees, and the occupancy
  // grid counts both faces of a wall as one crossing. Measured 0.905 of the
  // normals outward and 0.646 within 20 degrees before; with both faces'
  // normals fitted together (twoSheetPlane) 0.962 and 0.753, and with the
  // inner faces' patches decided from the outer faces across the wall
  // (sidesAcrossThinGaps) 0.974.
  const Scan scan =
      readScan(fs::path(CSGVOX_DATA_DIR) / "regressions" / "inversecsg-150-scanner.ply");
  PointCloud cloud{scan.cloud.points, {}};
  estimateNormals(cloud, 18);
  const double agreement = signAgreement(cloud.normals, scan.cloud.normals);
  std::size_t within = 0;  // directions within 20 degrees, sign ignored
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    within += std::abs(cloud.normals[i].dot(scan.cloud.normals[i])) >
              std::cos(20.0 * std::numbers::pi / 180.0);
  }
  const double directions = double(within) / double(cloud.size());
  std::printf("InverseCSG 150, scanner scan: %.4f of the normals outward, %.4f within 20 degrees\n",
              agreement, directions);
  EXPECT_GE(agreement, 0.965);
  EXPECT_GE(directions, 0.72);
}

TEST(OrientNormals, ExactSamplesAreNotSearchedForThinWalls) {
  // 60 000 points sampled from InverseCSG 060's mesh (no noise), normals
  // estimated from the positions: without noise every edge or curved
  // neighbourhood splits into two groups of offsets, so a search for thin
  // walls would find them everywhere. Measured 0.966 of the normals outward
  // (0.928 when the search ran on exact points too).
  const Scan scan = readScan(fs::path(CSGVOX_DATA_DIR) / "regressions" / "inversecsg-060-60k.ply");
  ASSERT_FALSE(scan.info.normalsEstimated);
  PointCloud cloud{scan.cloud.points, {}};
  estimateNormals(cloud, 18);
  const double agreement = signAgreement(cloud.normals, scan.cloud.normals);
  std::printf("InverseCSG 060, exact sample: %.4f of the normals outward\n", agreement);
  EXPECT_GE(agreement, 0.95);
}

TEST(OrientNormals, VisibilityAloneOrientsAClosedScan) {
  // Normals with random signs: visibility turns every smooth patch of the
  // clean flange scan outwards.
  const Scan scan = readScan(fs::path(CSGVOX_DATA_DIR) / "flange" / "scan.ply");
  std::vector<Vec3> normals = scan.cloud.normals;
  std::mt19937 rng(3);
  for (Vec3& n : normals) {
    if (rng() & 1u) n = -n;
  }
  const NearestNeighbors tree(scan.cloud.points);
  std::vector<std::uint32_t> hoods, hood;
  for (const Vec3& p : scan.cloud.points) {
    tree.kNearest(p, 18, hood);
    hoods.insert(hoods.end(), hood.begin(), hood.end());
  }
  orientNormals(scan.cloud.points, normals, hoods, 18);
  // Measured 0.971 on these 10 000 points (0.9999 on 100 000 points of the
  // same part); patches the rays leave open keep their random signs.
  EXPECT_GE(signAgreement(normals, scan.cloud.normals), 0.95);
}

TEST(OrientNormals, SameNormalsWithAnyNumberOfThreads) {
  test::RawScanOptions o;
  o.points = 6000;
  std::vector<Vec3> truth;
  const PointCloud raw = surfaceOf(test::makeRawScan("flange", o), truth);
  PointCloud one = raw, two = raw;
  estimateOnThreads(one, 1);
  estimateOnThreads(two, 2);
  EXPECT_EQ(one.normals, two.normals);
}

TEST(OrientNormals, SameNormalsOnThinWallsWithAnyNumberOfThreads) {
  // The tray's walls set the thin-wall mode (its patches flooded twice).
  const Scan scan = readScan(fs::path(CSGVOX_DATA_DIR) / "thin" / "thin_tray" / "scan_scanner.ply");
  PointCloud one{scan.cloud.points, {}}, two = one;
  estimateOnThreads(one, 1);
  estimateOnThreads(two, 2);
  EXPECT_EQ(one.normals, two.normals);
  EXPECT_EQ(one.normals, scan.cloud.normals);
}

TEST(OrientNormals, SameNormalsOnWallsThinnerThanTheNeighbourhoodsWithAnyNumberOfThreads) {
  // InverseCSG 150's walls: both faces' normals fitted together, and the
  // inner faces' patches decided across the walls.
  const Scan scan =
      readScan(fs::path(CSGVOX_DATA_DIR) / "regressions" / "inversecsg-150-scanner.ply");
  PointCloud one{scan.cloud.points, {}}, two = one;
  estimateOnThreads(one, 1);
  estimateOnThreads(two, 2);
  EXPECT_EQ(one.normals, two.normals);
}

TEST(OrientNormals, RejectsMismatchedSizes) {
  std::vector<Vec3> points(10, Vec3::Zero()), normals(9, Vec3::UnitZ());
  std::vector<std::uint32_t> hoods(20, 0);
  EXPECT_THROW(orientNormals(points, normals, hoods, 2), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
