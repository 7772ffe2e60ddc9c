// Detection on normals estimated from raw points: near sharp edges they
// blend the two faces, and without DetectOptions::estimatedNormals the later
// RANSAC stages explain those strips by small spurious surfaces.

#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "mesh/surface_sampler.h"
#include "part_list.h"
#include "primitives/normal_estimation.h"
#include "primitives/surface_detection.h"
#include "scanner_scan.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

// 20 000 points of a bundled part, normals dropped and estimated again.
PointCloud rawSample(const std::string& part) {
  SampleOptions so;
  so.points = 20000;
  PointCloud cloud = sampleSurface(readTreeJson(test::dataDir() / part / "tree.json"), so).cloud;
  cloud.normals.clear();
  estimateNormals(cloud, 18);
  return cloud;
}

TEST(DetectionOnEstimatedNormals, EdgeStripsDoNotBecomeSpuriousSurfaces) {
  const PointCloud cloud = rawSample("l_bracket");
  DetectOptions trusting;
  const DetectionResult plain = detectSurfaces(cloud, trusting);
  DetectOptions estimated;
  estimated.estimatedNormals = true;
  const DetectionResult raw = detectSurfaces(cloud, estimated);
  ASSERT_TRUE(raw.ok()) << raw.message;
  // Its 7 primitives have 13 faces (9 planes, 4 cylinders), as exact
  // normals give; trusting the estimated normals gives more (19: the
  // strips of an edge's last few points, whose normals stay blended).
  EXPECT_LE(raw.surfaces.size(), 15u) << raw.message;
  EXPECT_GT(plain.surfaces.size(), raw.surfaces.size()) << plain.message;
  std::size_t planes = 0;
  for (const Surface& s : raw.surfaces) planes += s.type() == SurfaceType::Plane;
  EXPECT_GE(planes, 9u) << raw.message;
}

// Given normals are trusted as before: the flag only matters for estimated
// ones, and a scan with exact normals gives the same surfaces either way
// when nothing is left over.
TEST(DetectionOnEstimatedNormals, ExactNormalsGiveTheSameSurfaces) {
  SampleOptions so;
  so.points = 10000;
  const PointCloud cloud =
      sampleSurface(readTreeJson(test::dataDir() / "plate_holes" / "tree.json"), so).cloud;
  DetectOptions estimated;
  estimated.estimatedNormals = true;
  const DetectionResult a = detectSurfaces(cloud);
  const DetectionResult b = detectSurfaces(cloud, estimated);
  ASSERT_EQ(a.surfaces.size(), b.surfaces.size());
  for (std::size_t i = 0; i < a.surfaces.size(); ++i) {
    EXPECT_EQ(a.surfaces[i].inliers, b.surfaces[i].inliers) << i;
  }
}

// The walls of small holes in a thin plate, from raw points: planes, as
// exact normals give. Before, RANSAC explained them by wide cylinders (made
// of nearly parallel estimated normals, touching two walls) or by wide
// cones and tori it refused after they took the walls' points, and the
// leftover test dropped the walls' points within epsilon of the plate's
// faces: 2 planes and 6 cylinders explained 90 % of the points (now 21
// planes, 4 cylinders and 3 cones explain 98.5 %).
TEST(DetectionOnEstimatedNormals, NarrowWallsOfAThinPlateArePlanes) {
  SampleOptions so;
  so.points = 50000;
  PointCloud cloud = sampleSurface(test::thinPlateWithTurnedHoles(), so).cloud;
  const std::vector<Vec3> truth = cloud.normals;
  estimateNormals(cloud, 18);
  DetectOptions estimated;
  estimated.estimatedNormals = true;
  const DetectionResult found = detectSurfaces(cloud, estimated);
  ASSERT_TRUE(found.ok()) << found.message;
  std::size_t planes = 0;
  for (const Surface& s : found.surfaces) planes += s.type() == SurfaceType::Plane;
  EXPECT_GE(planes, 15u) << found.message;  // 2 + 24 walls, some coplanar
  // The points of the walls (true normal across z) on a plane whose normal
  // is theirs within 5 degrees.
  std::size_t walls = 0, onTheirPlane = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (std::abs(truth[i].z()) > 0.1) continue;
    ++walls;
    const int s = found.assignment[i];
    if (s < 0) continue;
    const auto* plane = found.surfaces[std::size_t(s)].as<PlaneSurface>();
    onTheirPlane += plane != nullptr && std::abs(plane->normal.dot(truth[i])) > 0.996;
  }
  // (0.51 now: the rest lie on a few small cylinders and cones at the holes'
  // corners or on no surface; before, none did.)
  EXPECT_GE(double(onTheirPlane) / double(walls), 0.4) << onTheirPlane << " of " << walls;
}

// A scanner's own normals (noisy, from its range image) are given, not
// estimated, and blend the faces at edges as estimated ones do: detection
// measures their noise on the first stage's surfaces and treats them as
// estimated from the next stage on. Trusted as exact, they gave three times
// the surfaces (l_bracket's 20 000-point scanner scan: 41; now 14, as with
// estimatedNormals; countersunk_plate 46 -> 20, housing_complex 32 -> 16).
TEST(DetectionOnEstimatedNormals, AScannersOwnNormalsAreJudgedAsEstimatedOnes) {
  const PointCloud scanned = test::scannerScan("l_bracket", 20000, ScannerNormals::Scanner);
  ASSERT_TRUE(scanned.hasNormals());
  const DetectionResult measured = detectSurfaces(scanned);
  ASSERT_TRUE(measured.ok()) << measured.message;
  EXPECT_GT(measured.normalNoise, DetectOptions{}.scannerNormalNoise);
  EXPECT_TRUE(measured.rawNormals);
  EXPECT_LE(measured.surfaces.size(), 16u) << measured.message;  // 13 faces
  DetectOptions trusting;
  trusting.scannerNormalNoise = 1.0;  // never a scanner's
  const DetectionResult plain = detectSurfaces(scanned, trusting);
  ASSERT_TRUE(plain.ok()) << plain.message;
  EXPECT_FALSE(plain.rawNormals);
  EXPECT_GT(plain.surfaces.size(), 2 * measured.surfaces.size()) << plain.message;
}

// Model selection on a raw scan: the points of a face's strip between a few
// sigma and epsilon from it are mostly an edge's mixed pixels and blended
// corners, and under the full robust cost they made a bent cone, a sphere or
// a torus beat the plane or cylinder the bulk lies on. The bundled scanner
// scans of parts built from boxes, cylinders and half-spaces only, read as
// the main job reads them: no cone, sphere or torus (before the positions'
// truncated cost could veto them, seeds 1 and 2: housing_complex 4 and 1
// cones, pipe_tee 1 and 1 cones, plate_holes 1 and 2 tori, l_bracket 1 and 1
// tori).
TEST(DetectionOnEstimatedNormals, ScannerScansOfPrismaticPartsHaveNoCurvedExtras) {
  for (const char* part : {"housing_complex", "pipe_tee", "plate_holes", "l_bracket"}) {
    const Scan scan = readScan(test::dataDir() / part / "scan_scanner.ply");
    ASSERT_TRUE(scan.info.normalsEstimated) << part;
    for (const std::uint64_t seed : {1u, 2u}) {
      DetectOptions options;
      options.estimatedNormals = true;
      options.seed = seed;
      const DetectionResult found = detectSurfaces(scan.cloud, options);
      ASSERT_TRUE(found.ok()) << part << ": " << found.message;
      std::size_t curved = 0;
      for (const Surface& s : found.surfaces) {
        curved += s.type() == SurfaceType::Cone || s.type() == SurfaceType::Sphere ||
                  s.type() == SurfaceType::Torus;
      }
      EXPECT_EQ(curved, 0u) << part << " seed " << seed << ": " << found.message;
    }
  }
}

// Between the stages, a raw scan's points within a few neighbourhoods of an
// edge, whose normals blend the two faces by more than the noise measured
// inside them, go to their faces once the surfaces that live by the noise
// test are settled. Held to that noise, those bands were left to the later
// stages: the bundled scanner scans of these parts were explained to 88.6,
// 76.1, 85.3 and 91.1 % (seed 1, 13, 24, 13 and 8 surfaces); now to 99.5,
// 95.2, 98.9 and 98.8 % with 13, 23, 13 and 8.
TEST(DetectionOnEstimatedNormals, EdgeBandsGoToTheirFaces) {
  const std::vector<std::pair<const char*, std::size_t>> parts = {
      {"l_bracket", 13}, {"housing_complex", 24}, {"rotated_block", 13}, {"pipe_tee", 8}};
  for (const auto& [part, surfacesBefore] : parts) {
    const Scan scan = readScan(test::dataDir() / part / "scan_scanner.ply");
    ASSERT_TRUE(scan.info.normalsEstimated) << part;
    DetectOptions options;
    options.estimatedNormals = true;
    const DetectionResult found = detectSurfaces(scan.cloud, options);
    ASSERT_TRUE(found.ok()) << part << ": " << found.message;
    std::size_t explained = 0;
    for (const Surface& s : found.surfaces) explained += s.inliers.size();
    EXPECT_GE(double(explained), 0.94 * double(scan.cloud.size())) << part << ": " << found.message;
    EXPECT_LE(found.surfaces.size(), surfacesBefore) << part << ": " << found.message;
  }
}

}  // namespace
}  // namespace csgvox
