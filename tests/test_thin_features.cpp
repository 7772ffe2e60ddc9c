// Thin features found on the surfaces, and the finer grid the main job lays
// for them (primitives/thin_features.h, pipeline/detect_and_fit.h).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "io/scan_reader.h"
#include "pipeline/detect_and_fit.h"
#include "primitives/thin_features.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

// A square patch of a plane z = height, side 10 starting at x = x0, with
// the given normal, appended to the scan; returns its surface.
Surface patch(PointCloud& scan, double x0, double height, double nz) {
  Surface s;
  s.shape = PlaneSurface{Vec3(0, 0, nz), nz * height};
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j) {
      s.inliers.push_back(std::uint32_t(scan.points.size()));
      scan.points.emplace_back(x0 + 0.25 * i, 0.25 * j, height);
      scan.normals.emplace_back(0, 0, nz);
    }
  }
  return s;
}

ThinFeatureOptions within(double thickness) {
  ThinFeatureOptions o;
  o.maxThickness = thickness;
  o.reach = 0.5;
  return o;
}

TEST(ThinFeatures, OppositePlanesThatFaceEachOtherAreAWallOrASlot) {
  PointCloud scan;
  // A sheet 0.4 thick: its bottom faces down, its top up.
  const std::vector<Surface> wall{patch(scan, 0.0, 0.0, -1.0), patch(scan, 0.0, 0.4, 1.0)};
  std::vector<ThinFeature> found = findThinFeatures(scan, wall, within(1.0));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].kind, ThinKind::Wall);
  EXPECT_NEAR(found[0].thickness, 0.4, 1e-9);
  EXPECT_TRUE(findThinFeatures(scan, wall, within(0.3)).empty());  // thicker than asked

  // A gap 0.3 wide: the faces look at each other.
  PointCloud gapScan;
  const std::vector<Surface> slot{patch(gapScan, 0.0, 0.0, 1.0), patch(gapScan, 0.0, 0.3, -1.0)};
  found = findThinFeatures(gapScan, slot, within(1.0));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].kind, ThinKind::Slot);
  EXPECT_NEAR(found[0].thickness, 0.3, 1e-9);
}

TEST(ThinFeatures, PlanesSideBySideOrParallelAreNotThin) {
  PointCloud scan;
  // Opposite normals 0.4 apart, but 20 apart along x: nothing lies between.
  const std::vector<Surface> apart{patch(scan, 0.0, 0.0, -1.0), patch(scan, 20.0, 0.4, 1.0)};
  EXPECT_TRUE(findThinFeatures(scan, apart, within(1.0)).empty());
  // A step: both faces point up.
  PointCloud stepScan;
  const std::vector<Surface> step{patch(stepScan, 0.0, 0.0, 1.0), patch(stepScan, 0.0, 0.4, 1.0)};
  EXPECT_TRUE(findThinFeatures(stepScan, step, within(1.0)).empty());
}

TEST(ThinFeatures, ThinCylindersAreRodsOrHoles) {
  PointCloud scan;
  scan.points.assign(60, Vec3::Zero());
  scan.normals.assign(60, Vec3::UnitX());
  Surface rod, hole, wide;
  for (std::uint32_t i = 0; i < 60; ++i) rod.inliers.push_back(i);
  hole.inliers = wide.inliers = rod.inliers;
  rod.shape = CylinderSurface{Vec3::Zero(), Vec3::UnitZ(), 0.2};
  hole.shape = CylinderSurface{Vec3::Zero(), Vec3::UnitZ(), 0.3};
  hole.convex = false;
  wide.shape = CylinderSurface{Vec3::Zero(), Vec3::UnitZ(), 2.0};
  const std::vector<Surface> surfaces{rod, hole, wide};
  const std::vector<ThinFeature> found = findThinFeatures(scan, surfaces, within(1.0));
  ASSERT_EQ(found.size(), 2u);  // thinnest first, the wide one left out
  EXPECT_EQ(found[0].kind, ThinKind::Rod);
  EXPECT_DOUBLE_EQ(found[0].thickness, 0.4);
  EXPECT_EQ(found[1].kind, ThinKind::Hole);
  EXPECT_DOUBLE_EQ(found[1].thickness, 0.6);
  EXPECT_THROW(findThinFeatures(scan, surfaces, ThinFeatureOptions{}), std::invalid_argument);
}

// The thin parts (data/thin/README.md gives their true thickness) get a
// finer grid whose voxels are at most half the feature; the thickness found
// is the true one. Their noisy scans (sigma 0.5 % of D, about 0.37 mm) show
// the feature too, but keep the asked grid: voxels of half a millimetre
// would be under two noise sigmas.
TEST(ThinFeatures, TheThinPartsGetAFinerGridUnlessTheNoiseIsAsLarge) {
  const fs::path thin = fs::path(CSGVOX_DATA_DIR) / "thin";
  struct Case {
    const char* part;
    ThinKind kind;
    double thickness;  // mm, the part's true
  };
  for (const Case& c :
       {Case{"slotted_plate", ThinKind::Slot, 0.6}, Case{"thin_tray", ThinKind::Wall, 1.0},
        Case{"sheet_bracket", ThinKind::Wall, 1.5}}) {
    for (const bool noisy : {false, true}) {
      const Scan scan = readScan(thin / c.part / (noisy ? "scan_noisy.ply" : "scan.ply"));
      const SurfacesAndCandidates found = detectAndFit(scan.cloud);
      const std::string what = std::string(c.part) + (noisy ? " noisy" : " clean");
      ASSERT_TRUE(found.ok()) << what;
      ASSERT_FALSE(found.thin.empty()) << what;
      EXPECT_EQ(found.thin.front().kind, c.kind) << what;
      EXPECT_NEAR(found.thin.front().thickness, c.thickness, 0.1 * c.thickness) << what;

      DetectAndFitOptions off;
      off.finerGrid = false;
      const SurfacesAndCandidates coarse = detectAndFit(scan.cloud, off);
      EXPECT_EQ(coarse.resolution, 64) << what;
      if (noisy) {
        EXPECT_EQ(found.resolution, 64) << what;
        EXPECT_DOUBLE_EQ(found.grid.voxelSize(), coarse.grid.voxelSize()) << what;
        continue;
      }
      EXPECT_GT(found.resolution, 64) << what;
      EXPECT_LE(found.resolution, 128) << what;
      // Two voxels to the thinnest feature, unless capped at twice the resolution.
      EXPECT_TRUE(found.grid.voxelSize() <= 0.5 * found.thin.front().thickness * 1.02 ||
                  found.resolution == 128)
          << what << ": voxel " << found.grid.voxelSize();
      // (The grid's margin makes the ratio a little larger than the resolutions'.)
      EXPECT_NEAR(coarse.grid.voxelSize() / found.grid.voxelSize() / (found.resolution / 64.0), 1.0,
                  0.05)
          << what;
      // A finer grid that would not fit in memory is not laid.
      DetectAndFitOptions small;
      small.memoryLimit = std::size_t(
          voxelStageBytes(coarse.hypotheses.candidates.size(), coarse.grid.voxelCount()) * 1.5);
      EXPECT_EQ(detectAndFit(scan.cloud, small).resolution, 64) << what;
    }
  }
}

// The bundled parts have no feature under two voxels at res 64: their grid
// (and so their tree and its cost) is as asked.
TEST(ThinFeatures, TheRegularPartsKeepTheirResolution) {
  std::size_t scans = 0;
  for (const auto& entry : fs::directory_iterator(CSGVOX_DATA_DIR)) {
    for (const char* name : {"scan.ply", "scan_noisy.ply"}) {
      const fs::path path = entry.path() / name;
      if (!fs::exists(path)) continue;
      const SurfacesAndCandidates found = detectAndFit(readScan(path).cloud);
      ASSERT_TRUE(found.ok()) << path;
      EXPECT_TRUE(found.thin.empty()) << path << ": a " << thinKindName(found.thin.front().kind)
                                      << " " << found.thin.front().thickness << " thick";
      EXPECT_EQ(found.resolution, 64) << path;
      ++scans;
    }
  }
  EXPECT_EQ(scans, 24u);
}

}  // namespace
}  // namespace csgvox
