// The methods on the command line: `--method gp` (the published baseline on
// csgvox's detection) and `compare`, as a user runs them.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_helpers.h"

namespace csgvox {
namespace {

const std::string kCube = std::string(CSGVOX_DATA_DIR) + "/gp-baseline/cube.xyzn";

nlohmann::json readJson(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

// The box's exact tree from its six planes, for several seeds, the same tree
// again for the same seed, and the same with one thread or two.
TEST_F(Cli, GpFindsTheExactCubeAndIsSeeded) {
  for (const int seed : {1, 2, 3}) {
    const std::string out = "gp" + std::to_string(seed);
    const RunResult r = run(
        kCube + " --method gp -q --seed " + std::to_string(seed) + " -o " + (dir_ / out).string(),
        dir_, 300);
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json report = readJson(dir_ / out / "report.json");
    EXPECT_EQ(report["parameters"]["method"], "gp");
    EXPECT_EQ(report["tree"]["primitives"], 6) << slurp(dir_ / out / "tree.txt");
    EXPECT_EQ(report["tree"]["operations"], 5) << slurp(dir_ / out / "tree.txt");
    EXPECT_GE(report["metrics"]["voxel_iou"].get<double>(), 0.99);
    EXPECT_EQ(report["counts"]["library"], 6);
  }
  ASSERT_EQ(
      run(kCube + " --method gp -q --seed 2 --threads 1 -o " + (dir_ / "again").string(), dir_, 300)
          .code,
      0);
  EXPECT_EQ(slurp(dir_ / "again" / "tree.json"), slurp(dir_ / "gp2" / "tree.json"));
}

TEST_F(Cli, GpKeepsItsBestTreeAtTheTimeLimit) {
  // Long enough for detection, also in a sanitised build.
  const int limit = 3 * CSGVOX_TEST_SLOWDOWN;
  const RunResult r = run(kCube + " --method gp -q --stall 0 --generations 100000 --time-limit " +
                              std::to_string(limit) + " -o " + (dir_ / "t").string(),
                          dir_, 40 * limit);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json report = readJson(dir_ / "t" / "report.json");
  EXPECT_EQ(report["counts"]["stop"], "time_limit");
  EXPECT_TRUE(report["counts"]["time_limit_hit"].get<bool>());
  EXPECT_GE(report["metrics"]["voxel_iou"].get<double>(), 0.9);
}

// Friedrich's partitioning: the box's faces give its eight corners as
// partitions, and the searches on all points join them into the exact tree.
TEST_F(Cli, GpPartitionedFindsTheExactCubeAndReportsItsPartitions) {
  const RunResult r =
      run(kCube + " --method gp --partition -q --seed 1 -o " + (dir_ / "p").string(), dir_, 300);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json report = readJson(dir_ / "p" / "report.json");
  EXPECT_TRUE(report["parameters"]["partition"].get<bool>());
  EXPECT_EQ(report["tree"]["primitives"], 6) << slurp(dir_ / "p" / "tree.txt");
  EXPECT_EQ(report["tree"]["operations"], 5) << slurp(dir_ / "p" / "tree.txt");
  EXPECT_GE(report["metrics"]["voxel_iou"].get<double>(), 0.99);
  const nlohmann::json& parts = report["partitioning"]["partitions"];
  ASSERT_EQ(parts.size(), 8u);
  std::size_t points = 0;
  for (const nlohmann::json& p : parts) {
    EXPECT_EQ(p["primitives"], 3);
    points += p["points"].get<std::size_t>();
  }
  // Each point lies on one face, and each face is in four corners.
  EXPECT_EQ(points, 4 * report["input"]["points"].get<std::size_t>());
}

TEST_F(Cli, GpOptionsAreChecked) {
  EXPECT_EQ(run(kCube + " --method gp --population 2", dir_).code, 2);
  EXPECT_EQ(run(kCube + " --method gp --crossover 1.5", dir_).code, 2);
  EXPECT_EQ(run(kCube + " --method gp --operations max", dir_).code, 2);
  EXPECT_EQ(run(kCube + " --method magic", dir_).code, 2);
}

TEST_F(Cli, CompareShowsEveryMethodAndTheImportedTree) {
  const std::string base = std::string(CSGVOX_DATA_DIR) + "/gp-baseline/";
  const RunResult r = run("compare " + kCube + " -q --import-gp " + base + "cube.fit " + base +
                              "cube_expr.txt -o " + (dir_ / "cmp").string(),
                          dir_, 600);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* method : {"voxel", "hybrid", "gp", "import-gp"}) {
    EXPECT_NE(r.out.find(method), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(dir_ / "cmp" / method / "tree.json")) << method;
    EXPECT_TRUE(fs::exists(dir_ / "cmp" / method / "report.json")) << method;
  }
  const nlohmann::json summary = readJson(dir_ / "cmp" / "compare.json");
  ASSERT_EQ(summary["rows"].size(), 4u);
  for (const auto& row : summary["rows"]) {
    EXPECT_GE(row["voxel_iou"].get<double>(), 0.95) << row.dump();
    EXPECT_GT(row["primitives"].get<int>(), 0);
  }
  // The published code's tree for the cube is the cube (with redundant nodes).
  EXPECT_EQ(summary["rows"][1]["method"], "hybrid");
  EXPECT_EQ(summary["rows"][3]["method"], "import-gp");
  EXPECT_GT(summary["rows"][3]["operations"].get<int>(),
            summary["rows"][2]["operations"].get<int>());
  EXPECT_EQ(run("compare " + kCube + " --methods voxel,magic", dir_).code, 1);
  // The imported tree is measured on the same grid as the built ones.
  EXPECT_EQ(readJson(dir_ / "cmp" / "import-gp" / "report.json")["grid"]["resolution"],
            readJson(dir_ / "cmp" / "voxel" / "report.json")["grid"]["resolution"]);
}

// The repair search's options under their names, and under the names they
// had before (kept for one release): the same settings, reported under both.
TEST_F(Cli, RepairOptionsAndTheirOldNames) {
  const std::string common = kCube + " -q --res 24 --repair-generations 5 --no-preview ";
  ASSERT_EQ(run(common + "--repair-stall 3 --repair-searches 2 --no-finer-grid -o " +
                    (dir_ / "new").string(),
                dir_, 300)
                .code,
            0);
  ASSERT_EQ(run(common + "--refine-stall 3 --refine-searches 2 --no-refine-thin -o " +
                    (dir_ / "old").string(),
                dir_, 300)
                .code,
            0);
  const nlohmann::json a = readJson(dir_ / "new" / "report.json");
  const nlohmann::json b = readJson(dir_ / "old" / "report.json");
  EXPECT_EQ(a["parameters"]["repair_stall"], 3);
  EXPECT_EQ(a["parameters"]["repair_searches"], 2);
  EXPECT_EQ(a["parameters"]["refine_stall"], 3);
  EXPECT_EQ(a["parameters"], b["parameters"]);
  EXPECT_EQ(slurp(dir_ / "new" / "tree.json"), slurp(dir_ / "old" / "tree.json"));
  EXPECT_EQ(run(kCube + " --repair-searches 0", dir_).code, 2);
  EXPECT_EQ(run(kCube + " --repair-operations max", dir_).code, 2);
}

}  // namespace
}  // namespace csgvox
