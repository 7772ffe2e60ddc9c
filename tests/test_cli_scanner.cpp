// `csgvox sample --scanner`: the scanner model from the command line — raw
// xyz by default, scanner normals on request, the counts line, exact point
// counts, the same file for the same seed, and one-line refusals of bad
// options.

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "cli_helpers.h"
#include "core/csg_tree.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"

namespace csgvox {
namespace {

const std::string kTree = std::string(CSGVOX_DATA_DIR) + "/flange/tree.json";

TEST_F(Cli, SampleScannerWritesRawXyzAndPrintsTheCounts) {
  const fs::path scan = dir_ / "scan.ply";
  const RunResult r =
      run("sample '" + kTree + "' -o '" + scan.string() + "' --scanner --points 5000", dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* word : {"hits", "dropped for incidence", "mixed pixels", "outliers",
                           "5000 kept", " s:"}) {
    EXPECT_NE(r.err.find(word), std::string::npos) << word << "\n" << r.err;
  }
  const std::string bytes = slurp(scan);
  const std::string header = bytes.substr(0, bytes.find("end_header"));
  EXPECT_NE(header.find("element vertex 5000"), std::string::npos) << header;
  EXPECT_NE(header.find("binary_little_endian"), std::string::npos) << header;
  EXPECT_EQ(header.find("nx"), std::string::npos) << header;

  const Scan read = readScan(scan);
  EXPECT_EQ(read.info.pointsRead, 5000u);
  EXPECT_TRUE(read.info.normalsEstimated);  // the file had none
  // The points are near the flange's surface (noise, a few artifacts).
  const CsgTree tree = readTreeJson(kTree);
  const double d = tree.bounds().diagonal();
  std::size_t near = 0;
  for (const Vec3& p : read.cloud.points) near += std::abs(tree.value(p)) < 0.005 * d;
  EXPECT_GT(double(near), 0.97 * 5000);

  // The same seed gives the same file; scanner normals are written on request.
  const fs::path again = dir_ / "again.ply";
  ASSERT_EQ(run("sample '" + kTree + "' -o '" + again.string() +
                    "' --scanner --points 5000 --threads 1 --quiet",
                dir_)
                .code,
            0);
  EXPECT_EQ(slurp(again), bytes);
  const fs::path normals = dir_ / "normals.xyz";
  const RunResult n = run("sample '" + kTree + "' -o '" + normals.string() +
                              "' --scanner --points 1000 --scanner-normals scanner --setups 1 "
                              "--elevations 30 --views 6 --quiet",
                          dir_);
  ASSERT_EQ(n.code, 0) << n.err;
  const std::string text = slurp(normals);
  const std::string firstLine = text.substr(0, text.find('\n'));
  EXPECT_EQ(std::count(firstLine.begin(), firstLine.end(), ' '), 5) << firstLine;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1000);
}

TEST_F(Cli, SampleScannerRefusesBadOptionsInOneLine) {
  const std::string base = "sample '" + kTree + "' -o '" + (dir_ / "s.ply").string() + "' ";
  struct Bad {
    std::string args, named;
  };
  for (const Bad& b : {Bad{"--scanner --elevations 20,95", "--elevations"},
                       Bad{"--scanner --elevations 0", "--elevations"},
                       Bad{"--scanner --setups 3", "--setups"},
                       Bad{"--scanner --max-incidence 91", "--max-incidence"},
                       Bad{"--scanner --outliers -0.1", "--outliers"},
                       Bad{"--scanner --scanner-normals exact", "--scanner-normals"},
                       Bad{"--scanner --noise 0.01", "--noise"},
                       Bad{"--views 4", "--views"}}) {
    const RunResult r = run(base + b.args, dir_);
    EXPECT_EQ(r.code, 2) << b.args << "\n" << r.err;
    EXPECT_NE(r.err.find(b.named), std::string::npos) << b.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "s.ply")) << b.args;
  }
}

// Every bundled part carries a scanner scan: 20 000 raw x y z points near its
// tree's surface (data/make_scans.sh).
TEST(BundledScannerScans, EveryPartHasOneOfRawPointsNearItsTree) {
  std::vector<fs::path> parts;
  for (const fs::path& dir : {fs::path(CSGVOX_DATA_DIR), fs::path(CSGVOX_DATA_DIR) / "thin"}) {
    for (const auto& e : fs::directory_iterator(dir)) {
      if (fs::exists(e.path() / "tree.json")) parts.push_back(e.path());
    }
  }
  ASSERT_GE(parts.size(), 16u);
  for (const fs::path& part : parts) {
    const fs::path scan = part / "scan_scanner.ply";
    ASSERT_TRUE(fs::exists(scan)) << scan;
    const std::string bytes = slurp(scan);
    const std::string header = bytes.substr(0, bytes.find("end_header"));
    EXPECT_NE(header.find("element vertex 20000"), std::string::npos) << scan;
    EXPECT_EQ(header.find("nx"), std::string::npos) << scan;
    EXPECT_NE(header.find("binary_little_endian"), std::string::npos) << scan;
    // The binary data: float x y z per point.
    const std::size_t data = bytes.find("end_header\n") + 11;
    ASSERT_EQ(bytes.size() - data, 20000u * 3u * sizeof(float)) << scan;
    const CsgTree tree = readTreeJson(part / "tree.json");
    const double d = tree.bounds().diagonal();
    std::size_t near = 0;
    for (std::size_t i = 0; i < 20000; ++i) {
      float xyz[3];
      std::memcpy(xyz, bytes.data() + data + i * sizeof xyz, sizeof xyz);
      near += std::abs(tree.value(Vec3(xyz[0], xyz[1], xyz[2]))) < 0.005 * d;
    }
    EXPECT_GT(double(near), 0.97 * 20000) << scan;
  }
}

}  // namespace
}  // namespace csgvox
