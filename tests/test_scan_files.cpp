// Several files of one scan (a scanner's exports of its views or setups, in
// one frame): read together as one scan by readScans() and by the main job
// (`csgvox view1.ply view2.ply ...`); a mesh among them or too few points
// in all is refused naming the problem.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_helpers.h"
#include "io/errors.h"
#include "io/point_writer.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "mesh/surface_sampler.h"

namespace csgvox {
namespace {

// The points of `cloud` on one side of x = `split` (normals kept or not).
PointCloud side(const PointCloud& cloud, double split, bool below, bool normals) {
  PointCloud out;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if ((cloud.points[i].x() < split) != below) continue;
    out.points.push_back(cloud.points[i]);
    if (normals) out.normals.push_back(cloud.normals[i]);
  }
  return out;
}

class ScanFiles : public Cli {
 protected:
  // The flange sampled, cut in two at x = 0 and written as two raw files.
  void SetUp() override {
    Cli::SetUp();
    left_ = dir_ / "left.ply";
    right_ = dir_ / "right.ply";
    SampleOptions so;
    so.points = 6000;
    whole_ = sampleSurface(readTreeJson(test::dataDir() / "flange" / "tree.json"), so).cloud;
    writePointCloudPly(left_, side(whole_, 0.0, true, false));
    writePointCloudPly(right_, side(whole_, 0.0, false, false));
  }
  PointCloud whole_;
  fs::path left_;
  fs::path right_;
};

TEST_F(ScanFiles, ViewsAreReadAsOneScanWithNormalsEstimatedOnTheWhole) {
  const Scan s = readScans({left_, right_});
  EXPECT_EQ(s.cloud.size(), whole_.size());
  EXPECT_EQ(s.info.pointsRead, whole_.size());
  EXPECT_TRUE(s.info.normalsEstimated);
  ASSERT_EQ(s.info.files.size(), 2u);
  EXPECT_EQ(s.info.files[1], right_.string());
  // The normals are oriented as one surface: they face the sampled ones'
  // way on (nearly) every point, on both sides of the cut.
  const PointCloud left = side(whole_, 0.0, true, true);
  const PointCloud right = side(whole_, 0.0, false, true);
  std::size_t agree = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Vec3& truth = i < left.size() ? left.normals[i] : right.normals[i - left.size()];
    if (s.cloud.normals[i].dot(truth) > 0.0) ++agree;
  }
  EXPECT_GT(double(agree) / double(whole_.size()), 0.99);
  // One path is readScan's.
  EXPECT_EQ(readScans({left_}).cloud.size(), readScan(left_).cloud.size());
  EXPECT_TRUE(readScans({left_}).info.files.empty());
}

TEST_F(ScanFiles, NormalsAreKeptOnlyWhenEveryFileHasThem) {
  const fs::path withNormals = dir_ / "left-n.ply";
  const fs::path otherWithNormals = dir_ / "right-n.ply";
  writePointCloudPly(withNormals, side(whole_, 0.0, true, true));
  writePointCloudPly(otherWithNormals, side(whole_, 0.0, false, true));
  EXPECT_FALSE(readScans({withNormals, otherWithNormals}).info.normalsEstimated);
  EXPECT_TRUE(readScans({withNormals, right_}).info.normalsEstimated);
}

TEST_F(ScanFiles, AMeshOrTooFewPointsInAllIsRefusedNamingTheProblem) {
  const fs::path mesh = dir_ / "part.off";
  write(mesh, "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  try {
    readScans({left_, mesh});
    FAIL() << "a mesh was read as a view";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find(mesh.string() + ": is a mesh"), std::string::npos)
        << e.what();
  }
  const fs::path few = dir_ / "few.xyz";
  const fs::path others = dir_ / "others.xyz";
  write(few, "0 0 0\n1 0 0\n0 1 0\n");
  write(others, "0 0 1\n1 1 0\n");
  try {
    readScans({few, others});
    FAIL() << "five points were read as a scan";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("have 5 points; at least 100"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(readScans({left_, dir_ / "missing.ply"}), IoError);
  EXPECT_THROW(readScans({}), std::invalid_argument);
}

// The main job reads the two halves as one scan and says so: the tree is
// the one of the same points in one file.
TEST_F(ScanFiles, TheMainJobTakesSeveralFiles) {
  const fs::path out = dir_ / "out";
  const RunResult r = run("'" + left_.string() + "' '" + right_.string() + "' -o '" +
                              out.string() + "' --no-preview",
                          dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("read " + left_.string() + " and 1 more: " +
                       std::to_string(whole_.size()) + " points from 2 files"),
            std::string::npos)
      << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["input"]["points"].get<std::size_t>(), whole_.size());
  ASSERT_EQ(report["input"]["files"].size(), 2u);
  EXPECT_EQ(report["input"]["files"][0].get<std::string>(), left_.string());
  EXPECT_EQ(report["input"]["normals"].get<std::string>(), "estimated");

  PointCloud both = side(whole_, 0.0, true, false);
  const PointCloud right = side(whole_, 0.0, false, false);
  both.points.insert(both.points.end(), right.points.begin(), right.points.end());
  const fs::path one = dir_ / "both.ply";
  writePointCloudPly(one, both);
  const fs::path oneOut = dir_ / "one";
  const RunResult single =
      run("'" + one.string() + "' -o '" + oneOut.string() + "' --no-preview", dir_);
  ASSERT_EQ(single.code, 0) << single.err;
  EXPECT_EQ(slurp(out / "tree.json"), slurp(oneOut / "tree.json"));
}

}  // namespace
}  // namespace csgvox
