// The shared first half of the main job: the grid's frame (gridBox) and
// `csgvox detect` giving exactly the main job's surfaces and candidates.

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>

#include "cli_helpers.h"
#include "io/report.h"
#include "io/scan_reader.h"
#include "pipeline/detect_and_fit.h"
#include "pipeline/reconstruct.h"

namespace csgvox {
namespace {

Surface planeWith(const Vec3& normal, std::size_t inliers) {
  Surface s;
  s.shape = PlaneSurface{normal.normalized(), 0.0};
  s.inliers.assign(inliers, 0);
  return s;
}

// Points filling a box of half sizes h in the frame `axes`.
PointCloud boxPoints(const Mat3& axes, const Vec3& h) {
  PointCloud c;
  for (int i = 0; i <= 10; ++i) {
    for (int j = 0; j <= 10; ++j) {
      for (int k = 0; k <= 10; ++k) {
        const Vec3 local(h.x() * (i / 5.0 - 1), h.y() * (j / 5.0 - 1), h.z() * (k / 5.0 - 1));
        c.points.push_back(axes * local);
      }
    }
  }
  return c;
}

TEST(SurfaceDirection, IsThePlanesNormalOrTheAxisUnitAndNoneForASphere) {
  Surface s = planeWith(Vec3(0, 0, 2), 1);
  EXPECT_EQ(surfaceDirection(s), std::optional<Vec3>(Vec3::UnitZ()));
  s.shape = CylinderSurface{Vec3(1, 2, 3), Vec3(0, 3, 0), 1.0};
  EXPECT_EQ(surfaceDirection(s), std::optional<Vec3>(Vec3::UnitY()));
  s.shape = ConeSurface{Vec3::Zero(), Vec3(-1, 0, 0), 0.3};
  EXPECT_EQ(surfaceDirection(s), std::optional<Vec3>(-Vec3::UnitX()));
  s.shape = TorusSurface{Vec3::Zero(), Vec3(0, 0, -1), 2.0, 0.5};
  EXPECT_EQ(surfaceDirection(s), std::optional<Vec3>(-Vec3::UnitZ()));
  s.shape = SphereSurface{Vec3::Zero(), 1.0};
  EXPECT_FALSE(surfaceDirection(s).has_value());
  s.shape = CylinderSurface{Vec3::Zero(), Vec3::Zero(), 1.0};
  EXPECT_FALSE(surfaceDirection(s).has_value());
}

TEST(GridBox, FollowsTheHeaviestSurfaceDirections) {
  // A box turned by 20 degrees about z; its faces' planes give the frame.
  const Mat3 axes =
      Eigen::AngleAxisd(20.0 * std::numbers::pi / 180.0, Vec3::UnitZ()).toRotationMatrix();
  const PointCloud scan = boxPoints(axes, Vec3(10, 5, 2));
  const std::vector<Surface> surfaces = {planeWith(axes.col(2), 500), planeWith(axes.col(0), 300),
                                         planeWith(axes.col(1), 200)};
  const OrientedBox box = gridBox(scan, surfaces);
  // Axes ordered longest first: x (10), y (5), z (2) of the turned frame.
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(std::abs(box.axes.col(a).dot(axes.col(a))), 1.0, 1e-9);
  EXPECT_LT((box.halfSize - Vec3(10, 5, 2)).norm(), 1e-9);
  EXPECT_GT(box.axes.determinant(), 0.0);
}

TEST(GridBox, NoDirectionGivesTheMinimalBox) {
  const Mat3 axes = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const PointCloud scan = boxPoints(axes, Vec3(8, 4, 1));
  Surface sphere;
  sphere.shape = SphereSurface{Vec3::Zero(), 1.0};
  sphere.inliers.assign(100, 0);
  const OrientedBox box = gridBox(scan, std::vector<Surface>{sphere});
  EXPECT_LT((box.halfSize - Vec3(8, 4, 1)).norm(), 1e-6);
}

TEST(GridBox, ATiltedDirectionIsNotTakenWhenItsBoxIsMuchLarger) {
  // The only plane is tilted by 30 degrees from the box's faces: the
  // aligned box would be far larger than the minimal one, which is kept.
  const PointCloud scan = boxPoints(Mat3::Identity(), Vec3(10, 10, 10));
  const Mat3 tilt =
      Eigen::AngleAxisd(30.0 * std::numbers::pi / 180.0, Vec3::UnitX()).toRotationMatrix();
  const OrientedBox box = gridBox(scan, std::vector<Surface>{planeWith(tilt.col(2), 100)});
  EXPECT_NEAR(box.halfSize.prod(), 1000.0, 1e-6);
}

// `csgvox detect --res 64` writes the very surfaces and candidates the main
// job optimises over.
TEST_F(Cli, DetectGivesTheMainJobsSurfacesAndCandidates) {
  for (const char* part : {"plate_holes", "flange"}) {
    SCOPED_TRACE(part);
    const fs::path scanPath = test::dataDir() / part / "scan_noisy.ply";
    const fs::path out = dir_ / part;
    const RunResult r = run(
        "detect '" + scanPath.string() + "' -q --res 64 --seed 3 -o '" + out.string() + "'", dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    ReadOptions ro;
    ro.seed = 3;
    const Scan scan = readScan(scanPath, ro);
    ReconstructOptions o;
    o.seed = 3;
    o.resolution = 64;
    const Reconstruction rec = reconstruct(scan.cloud, o);
    ASSERT_TRUE(rec.ok()) << rec.message;
    EXPECT_EQ(nlohmann::ordered_json::parse(slurp(out / "surfaces.json")),
              surfacesJson(scanPath.string(), rec.detection));
    EXPECT_EQ(nlohmann::ordered_json::parse(slurp(out / "candidates.json")),
              candidatesJson(scanPath.string(), rec.hypotheses));
  }
}

}  // namespace
}  // namespace csgvox
