// The csgvox executable as a user runs it: help, exit codes, one-line errors
// naming the file, no partial outputs, and the sample/eval/render round trip
// on every bundled part.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_helpers.h"
#include "io/mesh_files.h"
#include "mesh/mesh_solid.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

TEST_F(Cli, HelpListsTheCommands) {
  const RunResult r = run("--help", dir_);
  EXPECT_EQ(r.code, 0);
  for (const char* word : {"detect", "sample", "render", "eval", "--res", "--seed"}) {
    EXPECT_NE(r.out.find(word), std::string::npos) << word;
  }
  for (const char* cmd : {"sample", "render", "eval"}) {
    const RunResult c = run(std::string(cmd) + " --help", dir_);
    EXPECT_EQ(c.code, 0) << cmd;
    EXPECT_NE(c.out.find("TREE"), std::string::npos) << cmd;
  }
  const RunResult d = run("detect --help", dir_);
  EXPECT_EQ(d.code, 0);
  EXPECT_NE(d.out.find("--epsilon"), std::string::npos);
}

TEST_F(Cli, BadUsageExitsWithTwo) {
  EXPECT_EQ(run("", dir_).code, 2);
  EXPECT_EQ(run("scan.ply --no-such-flag", dir_).code, 2);
  EXPECT_EQ(run("scan.ply --res 0", dir_).code, 2);
  EXPECT_EQ(run("scan.ply --res 100000", dir_).code, 2);
  EXPECT_EQ(run("sample", dir_).code, 2);
}

TEST_F(Cli, BadScansGiveOneLineNamingTheFile) {
  const fs::path missing = dir_ / "missing.ply";
  expectCleanError("'" + missing.string() + "' -o '" + (dir_ / "out").string() + "'",
                   missing.string());
  fs::create_directories(dir_ / "adir.ply");
  expectCleanError("'" + (dir_ / "adir.ply").string() + "'", (dir_ / "adir.ply").string());
  const std::map<std::string, std::string> bad = {
      {"empty.ply", ""},
      {"header.ply", "plx\nformat ascii 1.0\nend_header\n"},
      {"truncated.ply", asciiPly(500).substr(0, asciiPly(500).size() / 2)},
      {"nan.ply", asciiPly(200) + ""},
      {"few.ply", asciiPly(20)},
      {"zeronormal.xyz", "0 0 0 0 0 0\n"},
      {"garbage.xyz", "hello world\n"},
      {"unknown.abc", "1 2 3\n"},
  };
  for (const auto& [name, text] : bad) {
    std::string content = text;
    if (name == "nan.ply") {
      content = asciiPly(200);
      content.replace(content.find("end_header\n") + 11, 1, "nan");
    }
    if (name == "zeronormal.xyz") {
      std::ostringstream s;
      for (int i = 0; i < 300; ++i) s << i << " " << i % 7 << " " << i % 11 << " 0 0 0\n";
      content = s.str();
    }
    write(dir_ / name, content);
    SCOPED_TRACE(name);
    expectCleanError("'" + (dir_ / name).string() + "' -o '" + (dir_ / "out").string() + "'",
                     (dir_ / name).string());
    // Nothing is written for a scan that could not be read.
    EXPECT_FALSE(fs::exists(dir_ / "out" / "report.json"));
  }
}

TEST_F(Cli, BadTreesGiveOneLineAndNoOutput) {
  write(dir_ / "bad.json",
        "{\"root\": {\"type\": \"sphere\", \"radius\": -1, \"center\": [0,0,0]}}");
  expectCleanError(
      "sample '" + (dir_ / "bad.json").string() + "' -o '" + (dir_ / "s.ply").string() + "'",
      (dir_ / "bad.json").string());
  EXPECT_FALSE(fs::exists(dir_ / "s.ply"));
  write(dir_ / "notjson.json", "{ this is not json");
  expectCleanError(
      "render '" + (dir_ / "notjson.json").string() + "' -o '" + (dir_ / "m.ply").string() + "'",
      (dir_ / "notjson.json").string());
  EXPECT_FALSE(fs::exists(dir_ / "m.ply"));
}

TEST_F(Cli, RenderRefusesUnknownFormatsAndOverwritingItsInput) {
  const fs::path tree = test::dataDir() / test::partNames().front() / "tree.json";
  fs::copy_file(tree, dir_ / "tree.json");
  const std::string before = slurp(dir_ / "tree.json");
  expectCleanError(
      "render '" + (dir_ / "tree.json").string() + "' -o '" + (dir_ / "x.docx").string() + "'",
      (dir_ / "x.docx").string());
  expectCleanError(
      "render '" + (dir_ / "tree.json").string() + "' -o '" + (dir_ / "tree.json").string() + "'",
      (dir_ / "tree.json").string());
  EXPECT_EQ(slurp(dir_ / "tree.json"), before);
}

TEST_F(Cli, MainJobWritesTheTreeItsExportsAndAReport) {
  fs::copy_file(test::dataDir() / "plate_holes" / "scan.ply", dir_ / "scan.ply");
  const RunResult r = run("'" + (dir_ / "scan.ply").string() + "' --res 64 --seed 3", dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("10000 points"), std::string::npos) << r.err;
  const fs::path out = dir_ / "scan-csgvox";
  for (const char* f : {"tree.json", "tree.scad", "tree.txt", "mesh.ply", "report.json"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  const auto j = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(j["status"], "ok");
  EXPECT_EQ(j["input"]["points"], 10000);
  EXPECT_LE(j["tree"]["primitives"].get<int>(), 5 + 2);
  EXPECT_LT(j["metrics"]["chamfer_relative"].get<double>(), 0.005);
  EXPECT_GT(j["metrics"]["within_1pct"].get<double>(), 0.99);
  // Phase 2's selection is among its candidates; the union holds at least
  // one member; the stage line gives the report's counts.
  const int chosen = j["counts"]["chosen"].get<int>(),
            selected = j["counts"]["selected"].get<int>(),
            candidates = j["counts"]["union_candidates"].get<int>();
  EXPECT_LE(selected, candidates);
  EXPECT_GE(chosen, 1);
  EXPECT_NE(r.err.find("optimisation: " + std::to_string(chosen) + " union member"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(std::to_string(selected) + " of " + std::to_string(candidates) +
                       " candidates selected"),
            std::string::npos)
      << r.err;
  // The same seed gives the same tree.
  const std::string first = slurp(out / "tree.json");
  ASSERT_EQ(run("'" + (dir_ / "scan.ply").string() + "' --res 64 --seed 3 -q", dir_).code, 0);
  EXPECT_EQ(slurp(out / "tree.json"), first);
}

TEST_F(Cli, MainJobOpensTheBoresOfAScannerScan) {
  // The pipe tee's scanner scan sees its bores near their mouths: the labels
  // line and report.json say how many voxels their completion opened (the
  // tree's IoU is tested in test_scanner_scans).
  const RunResult r = run("'" + (test::dataDir() / "pipe_tee" / "scan_scanner.ply").string() +
                              "' --no-preview -o '" + (dir_ / "out").string() + "'",
                          dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "out" / "report.json"));
  const long opened = j["counts"]["bore_voxels_opened"].get<long>();
  EXPECT_EQ(j["counts"]["bores_seen"].get<int>(), 2);
  EXPECT_GT(opened, 3000);
  EXPECT_NE(r.err.find("; " + std::to_string(opened) + " opened in 2 bores seen around their axis"),
            std::string::npos)
      << r.err;
}

TEST_F(Cli, MainJobRefusesAScanWithoutSurfaces) {
  // Points scattered through a cube with scattered normals: no plane,
  // cylinder, cone, sphere or torus explains them.
  std::vector<std::array<double, 6>> pts;
  std::uint64_t state = 12345;
  const auto next = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53);
  };
  for (int i = 0; i < 400; ++i) {
    const double a = 2.0 * 3.14159265358979 * next(), z = 2.0 * next() - 1.0;
    const double r = std::sqrt(1.0 - z * z);
    pts.push_back({10 * next(), 10 * next(), 10 * next(), r * std::cos(a), r * std::sin(a), z});
  }
  write(dir_ / "cloud.ply", pointsPly(pts));
  expectCleanError(
      "'" + (dir_ / "cloud.ply").string() + "' -q -o '" + (dir_ / "out").string() + "'",
      (dir_ / "cloud.ply").string());
  EXPECT_FALSE(fs::exists(dir_ / "out" / "report.json"));
}

TEST_F(Cli, MainJobRefusesAScanOfOnePlane) {
  std::vector<std::array<double, 6>> pts;
  for (int i = 0; i < 50; ++i) {
    for (int j = 0; j < 30; ++j) pts.push_back({double(i), double(j), 0, 0, 0, 1});
  }
  write(dir_ / "plane.ply", pointsPly(pts));
  expectCleanError(
      "'" + (dir_ / "plane.ply").string() + "' -q -o '" + (dir_ / "out").string() + "'",
      (dir_ / "plane.ply").string());
  EXPECT_FALSE(fs::exists(dir_ / "out" / "report.json"));
}

TEST_F(Cli, OpenScanIsClosedByTheWindingNumber) {
  // The documented fallback for a scan that is not closed: the winding
  // number closes it the shortest way. A tube without caps (radius 10,
  // length 40) becomes a solid cylinder.
  std::vector<std::array<double, 6>> pts;
  for (int i = 0; i < 80; ++i) {
    for (int k = 0; k < 60; ++k) {
      const double a = 2.0 * 3.14159265358979 * (i + 0.5 * (k % 2)) / 80.0;
      pts.push_back(
          {10 * std::cos(a), 10 * std::sin(a), 40.0 * k / 59.0, std::cos(a), std::sin(a), 0});
    }
  }
  write(dir_ / "tube.ply", pointsPly(pts));
  const RunResult r =
      run("'" + (dir_ / "tube.ply").string() + "' -q -o '" + (dir_ / "out").string() + "'", dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "out" / "tree.json"));
  EXPECT_EQ(j["root"]["type"], "cylinder") << j.dump();
  EXPECT_NEAR(j["root"]["radius"].get<double>(), 10.0, 0.01);
  EXPECT_NEAR(j["root"]["height"].get<double>(), 40.0, 0.5);
}

TEST_F(Cli, AbsurdResolutionsAreRefused) {
  fs::copy_file(test::dataDir() / "plate_holes" / "scan.ply", dir_ / "scan.ply");
  const std::string scan = "'" + (dir_ / "scan.ply").string() + "'";
  for (const char* res : {"0", "1", "-5", "100000", "abc"}) {
    const RunResult r = run(scan + " --res " + res + " -o '" + (dir_ / "out").string() + "'", dir_);
    EXPECT_EQ(r.code, 2) << res;
    EXPECT_NE(r.err.find("--res"), std::string::npos) << res << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << res;
  }
}

TEST_F(Cli, ResolutionBeyondTheMemoryLimitIsRefusedBeforeLabelling) {
  // housing_complex at 1024 voxels: about 230 million voxels for 100+
  // candidates, far above the 4 GiB limit; it must fail at once with the
  // largest resolution that fits, not exhaust memory.
  fs::copy_file(test::dataDir() / "housing_complex" / "scan.ply", dir_ / "scan.ply");
  const RunResult r = run(
      "'" + (dir_ / "scan.ply").string() + "' -q --res 1024 -o '" + (dir_ / "out").string() + "'",
      dir_);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("use a resolution of at most"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "report.json"));
}

// ---- sample → eval on every bundled part ----------------------------------

class CliRoundTrip : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override { dir_ = test::freshTempDir("roundtrip-" + GetParam()); }
  void TearDown() override { fs::remove_all(dir_); }
  nlohmann::json evalOf(const std::string& scanArgs) {
    const std::string tree = "'" + (test::dataDir() / GetParam() / "tree.json").string() + "'";
    const fs::path scan = dir_ / "s.ply";
    const RunResult s = run("sample " + tree + " -o '" + scan.string() + "' " + scanArgs, dir_);
    EXPECT_EQ(s.code, 0) << s.err;
    const RunResult e = run("eval " + tree + " '" + scan.string() + "' --json", dir_);
    EXPECT_EQ(e.code, 0) << e.err;
    return nlohmann::json::parse(e.out);
  }
  fs::path dir_;
};

TEST_P(CliRoundTrip, CleanSampleFitsExactly) {
  const auto j = evalOf("--points 20000 --seed 11");
  EXPECT_EQ(j["points"], 20000);
  EXPECT_LT(j["rmse_relative"].get<double>(), 1e-7);
  EXPECT_LT(j["surface_rmse_relative"].get<double>(), 5e-4);
  EXPECT_DOUBLE_EQ(j["within_1pct"].get<double>(), 1.0);
  EXPECT_GT(j["normal_agreement"].get<double>(), 0.99);
}

TEST_P(CliRoundTrip, NoisySampleErrorIsTheNoise) {
  const double sigma = 0.005;
  const auto j = evalOf("--points 20000 --seed 12 --noise " + std::to_string(sigma));
  // Noise is relative to the tree's diagonal; eval reports relative to the
  // (slightly larger, noisy) scan's diagonal.
  EXPECT_NEAR(j["rmse_relative"].get<double>() / sigma, 1.0, 0.15);
  EXPECT_NEAR(j["surface_rmse_relative"].get<double>() / sigma, 1.0, 0.15);
}

INSTANTIATE_TEST_SUITE_P(BundledParts, CliRoundTrip, ::testing::ValuesIn(test::partNames()),
                         [](const auto& info) { return info.param; });

// ---- the main job's outputs in OpenSCAD --------------------------------------

bool haveOpenScad() { return std::system("openscad --version > /dev/null 2>&1") == 0; }

class MainJobScad : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override { dir_ = test::freshTempDir("mainjob-scad-" + GetParam()); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// What a user does with the result: open OUTDIR/tree.scad in OpenSCAD. It
// must render the solid that OUTDIR/mesh.ply shows.
TEST_P(MainJobScad, TreeScadRendersTheSolidOfMeshPly) {
  if (!haveOpenScad()) {
    GTEST_SKIP() << "openscad is not installed (scripts/install-deps.sh installs it)";
  }
  const fs::path out = dir_ / "out";
  const RunResult r = run("'" + (test::dataDir() / GetParam() / "scan_noisy.ply").string() +
                              "' -q -o '" + out.string() + "'",
                          dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string cmd = "openscad -o '" + (dir_ / "openscad.stl").string() + "' '" +
                          (out / "tree.scad").string() + "' > '" + (dir_ / "log.txt").string() +
                          "' 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "openscad failed, see " << (dir_ / "log.txt");
  const TriangleMesh scad = readMesh(dir_ / "openscad.stl");
  const TriangleMesh mesh = readMesh(out / "mesh.ply");
  Aabb box = mesh.bounds();
  const Aabb sb = scad.bounds();
  box.min = box.min.cwiseMin(sb.min);
  box.max = box.max.cwiseMax(sb.max);
  const double voxel = box.diagonal() / 400.0;
  const MeshSolid scadSolid(scad, voxel), meshSolid(mesh, voxel);
  const double iou = test::sampledIou(
      box, [&](const Vec3& p) { return scadSolid.contains(p); },
      [&](const Vec3& p) { return meshSolid.contains(p); }, 200000, 3);
  EXPECT_GE(iou, 0.99);
  RecordProperty("iou", std::to_string(iou));
}

INSTANTIATE_TEST_SUITE_P(BundledParts, MainJobScad, ::testing::ValuesIn(test::partNames()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace csgvox
