// The CAD outputs from the command line: the main job writes tree.step,
// tree.csg and preview.png and lists them in report.json (--no-preview skips
// the picture and removes an older one); render writes each format; a tree
// whose solid OpenCASCADE cannot build is one error line naming the problem.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cad/step_export.h"
#include "cli_helpers.h"
#include "io/csg_reader.h"
#include "io/png_file.h"
#include "io/tree_json.h"

namespace csgvox {
namespace {

std::vector<std::string> outputsOf(const fs::path& report) {
  const auto j = nlohmann::json::parse(slurp(report));
  return j.at("outputs").get<std::vector<std::string>>();
}

TEST_F(Cli, TheMainJobWritesTheCadOutputsAndListsThem) {
  const fs::path out = dir_ / "out";
  const std::string scan = (test::dataDir() / "plate_holes" / "scan.ply").string();
  const RunResult r = run("'" + scan + "' -o '" + out.string() + "' --quiet", dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const bool step = stepExportAvailable();
  for (const char* name : {"tree.csg", "preview.png"}) EXPECT_TRUE(fs::exists(out / name)) << name;
  EXPECT_EQ(fs::exists(out / "tree.step"), step);
  std::vector<std::string> expected = {"tree.json", "tree.scad", "tree.txt", "tree.csg"};
  if (step) expected.push_back("tree.step");
  for (const char* name : {"tree.FCMacro", "preview.png", "mesh.ply", "report.json"}) {
    expected.push_back(name);
  }
  EXPECT_EQ(outputsOf(out / "report.json"), expected);
  // The seconds of the steps after the tree, in the order they are made;
  // tree.step is built on a thread of its own beside the others, and its CPU
  // seconds are that thread's (never more than its wall-clock seconds).
  const auto report = nlohmann::ordered_json::parse(slurp(out / "report.json"));
  std::vector<std::string> steps;
  for (const auto& [key, seconds] : report.at("timings_s").items()) {
    if (key == "export" || key == "step" || key == "preview" || key == "metrics") {
      steps.push_back(key);
    }
    EXPECT_GE(seconds.get<double>(), 0.0) << key;
    if (key != "refine") {
      EXPECT_GE(report.at("cpu_s").at(key).get<double>(), 0.0) << key;
    }
  }
  EXPECT_EQ(steps, (std::vector<std::string>{"export", "step", "preview", "metrics"}));
  EXPECT_LE(report.at("cpu_s").at("step").get<double>(),
            report.at("timings_s").at("step").get<double>() + 0.01);

  const CsgTree tree = readTreeJson(out / "tree.json");
  EXPECT_EQ(readCsg(out / "tree.csg").primitiveCount(), tree.primitiveCount());
  const RgbImage png = readPng(out / "preview.png");
  EXPECT_GT(png.width, png.height);  // the solid and the scan side by side
  if (step) {
    const BrepSummary s = readStepSummary(out / "tree.step");
    EXPECT_EQ(s.solids, 1u);
    EXPECT_TRUE(s.valid);
    EXPECT_TRUE(s.closed);
  }

  // Again without the preview: the older picture does not stay behind.
  const RunResult again =
      run("'" + scan + "' -o '" + out.string() + "' --quiet --no-preview", dir_);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_FALSE(fs::exists(out / "preview.png"));
  const auto listed = outputsOf(out / "report.json");
  EXPECT_EQ(std::count(listed.begin(), listed.end(), "preview.png"), 0);
}

TEST_F(Cli, RenderWritesStepCsgAndPng) {
  const std::string tree = (test::dataDir() / "knob" / "tree.json").string();
  const std::string scan = (test::dataDir() / "knob" / "scan_noisy.ply").string();
  EXPECT_EQ(run("render '" + tree + "' -o '" + (dir_ / "k.csg").string() + "' -q", dir_).code, 0);
  EXPECT_EQ(readCsg(dir_ / "k.csg").primitiveCount(), 6u);
  const RunResult png = run("render '" + tree + "' -o '" + (dir_ / "k.png").string() +
                                "' --scan '" + scan + "' --size 96 -q",
                            dir_);
  ASSERT_EQ(png.code, 0) << png.err;
  EXPECT_EQ(readPng(dir_ / "k.png").width, 2 * 96);
  const RunResult alone =
      run("render '" + tree + "' -o '" + (dir_ / "k1.png").string() + "' --size 96 -q", dir_);
  ASSERT_EQ(alone.code, 0) << alone.err;
  EXPECT_EQ(readPng(dir_ / "k1.png").width, 96);
  if (!stepExportAvailable()) GTEST_SKIP() << "built without OpenCASCADE";
  const RunResult step =
      run("render '" + tree + "' -o '" + (dir_ / "k.step").string() + "' -q", dir_);
  ASSERT_EQ(step.code, 0) << step.err;
  EXPECT_EQ(readStepSummary(dir_ / "k.step").solids, 1u);
}

TEST_F(Cli, AnEmptySolidIsOneErrorLineAndNoStepFile) {
  if (!stepExportAvailable()) GTEST_SKIP() << "built without OpenCASCADE";
  write(dir_ / "apart.json",
        R"({"root": {"op": "intersection", "children": [
             {"type": "sphere", "name": "a", "center": [0, 0, 0], "radius": 1},
             {"type": "sphere", "name": "b", "center": [5, 0, 0], "radius": 1}]}})");
  expectCleanError(
      "render '" + (dir_ / "apart.json").string() + "' -o '" + (dir_ / "apart.step").string() + "'",
      "empty");
  EXPECT_FALSE(fs::exists(dir_ / "apart.step"));
}

}  // namespace
}  // namespace csgvox
