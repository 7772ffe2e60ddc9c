// The designed tree in tree.json (frame, units, parameters, patterns beside
// the explicit primitives), in tree.txt (named patterns) and report.json's
// design section; render's round trip through tree.json; a turned scan
// through the main job.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "cli_helpers.h"
#include "design/designed_tree.h"
#include "design/part_frame.h"
#include "io/design_json.h"
#include "io/point_writer.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

CsgTree part(const std::string& name) { return readTreeJson(test::dataDir() / name / "tree.json"); }

// A part turned and moved, so that its frame is not the world's.
CsgTree turnedFlange() {
  test::Rng rng(11);
  return transformedTree(part("flange"), test::randomRotation(rng), Vec3(3, -7, 20));
}

TEST(DesignJson, TreeJsonHoldsTheDesignAndReadsBack) {
  const DesignedTree d = designTree(turnedFlange());
  std::ostringstream out;
  writeDesignedTreeJson(out, d);
  const auto j = nlohmann::json::parse(out.str());
  ASSERT_TRUE(j.contains("frame"));
  EXPECT_EQ(j.at("units"), "mm");
  ASSERT_EQ(j.at("parameters").size(), d.parameters.size());
  EXPECT_EQ(j.at("parameters").front().at("name"), d.parameters.front().name);
  ASSERT_EQ(j.at("patterns").size(), 1u);
  const auto& p = j.at("patterns").front();
  EXPECT_EQ(p.at("kind"), "circular");
  EXPECT_EQ(p.at("count"), 6);
  EXPECT_EQ(p.at("radius"), 38.0);
  EXPECT_EQ(p.at("members").size(), 6u);
  // The primitives are explicit: the tree reads back as the designed tree.
  std::istringstream in(out.str());
  const CsgTree back = readTreeJson(in);
  EXPECT_TRUE(back.structurallyEqual(d.tree(), 0.0));
  // The frame reads back, and designing the read tree in it gives the same
  // parameters (what render does).
  const fs::path file = test::freshTempDir("design-json") / "tree.json";
  writeDesignedTreeJson(file, d);
  const std::optional<PartFrame> frame = readTreeFrame(file);
  ASSERT_TRUE(frame);
  EXPECT_TRUE(frame->rotation.isApprox(d.frame.rotation, 1e-15));
  const DesignedTree again = designTree(readTreeJson(file), *frame, {});
  ASSERT_EQ(again.parameters.size(), d.parameters.size());
  for (std::size_t i = 0; i < d.parameters.size(); ++i) {
    EXPECT_EQ(again.parameters[i].name, d.parameters[i].name);
    EXPECT_NEAR(again.parameters[i].value, d.parameters[i].value, 1e-9) << d.parameters[i].name;
  }
  fs::remove_all(file.parent_path());
}

TEST(DesignJson, ATreeWithoutAFrameHasNone) {
  const fs::path file = test::dataDir() / "flange" / "tree.json";
  EXPECT_FALSE(readTreeFrame(file));
}

TEST(DesignJson, TreeTxtNamesThePattern) {
  const DesignedTree d = designTree(part("plate_holes"));
  std::ostringstream out;
  writeTreeText(out, d);
  EXPECT_NE(out.str().find("\nbolt_grid = lattice(hole_1, hole_2, hole_3, hole_4; count = 2"),
            std::string::npos)
      << out.str();
}

TEST(DesignJson, ReportSaysWhatWasSnapped) {
  const DesignedTree d = designTree(turnedFlange());
  const auto r = designReportJson(d, 0.5);
  EXPECT_EQ(r.at("parameters"), d.parameters.size());
  EXPECT_EQ(r.at("snapped"), d.snappedCount());
  EXPECT_GT(d.snappedCount(), 10);
  EXPECT_EQ(r.at("patterns"), 1u);
  EXPECT_EQ(r.at("frame_is_world"), false);
  EXPECT_GE(r.at("iou_to_fitted").get<double>(), 0.999);
  double largest = 0.0;
  for (const auto& v : r.at("values")) {
    if (v.at("snapped")) largest = std::max(largest, std::abs(v.at("change").get<double>()));
  }
  EXPECT_EQ(r.at("largest_change").get<double>(), largest);
}

// The parameters a point holds (finite uncertainty) of a job's tree.json:
// (value, uncertainty, snapped), in value order.
struct HeldValue {
  double value, uncertainty;
  bool snapped;
};
std::vector<HeldValue> heldValues(const fs::path& treeJson) {
  std::ifstream in(treeJson);
  const auto j = nlohmann::json::parse(in);
  std::vector<HeldValue> out;
  for (const auto& p : j.at("parameters")) {
    if (p.at("kind") == "count" || p.at("uncertainty").is_null()) continue;
    out.push_back({p.at("value").get<double>(), p.at("uncertainty").get<double>(),
                   p.at("snapped").get<bool>()});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.value < b.value; });
  return out;
}

// The main job on a bundled scan and on the same scan turned and moved: the
// parameters the points hold are the same, the snapped ones exactly, the
// others within their uncertainty; the frame carries the turn.
TEST(DesignJson, TurnedScanGivesTheSameParametersThroughTheJob) {
  const fs::path dir = test::freshTempDir("TurnedScanGivesTheSameParametersThroughTheJob");
  for (const std::string name : {"plate_holes", "l_bracket"}) {
    SCOPED_TRACE(name);
    const fs::path scanPath = test::dataDir() / name / "scan.ply";
    Scan scan = readScan(scanPath);
    test::Rng rng(3);
    const Mat3 r = test::randomRotation(rng);
    const Vec3 t(12.5, -40.0, 7.0);
    for (Vec3& p : scan.cloud.points) p = r * p + t;
    for (Vec3& n : scan.cloud.normals) n = r * n;
    const fs::path turned = dir / (name + "_turned.ply");
    writePointCloudPly(turned, scan.cloud);
    const fs::path a = dir / (name + "_a"), b = dir / (name + "_b");
    ASSERT_EQ(run("'" + scanPath.string() + "' -o '" + a.string() + "'", dir, 600).code, 0);
    ASSERT_EQ(run("'" + turned.string() + "' -o '" + b.string() + "'", dir, 600).code, 0);
    const auto va = heldValues(a / "tree.json"), vb = heldValues(b / "tree.json");
    ASSERT_EQ(va.size(), vb.size());
    ASSERT_GE(va.size(), 10u);
    for (std::size_t i = 0; i < va.size(); ++i) {
      EXPECT_EQ(va[i].snapped, vb[i].snapped) << i << " " << va[i].value << " " << vb[i].value;
      if (va[i].snapped && vb[i].snapped) {
        EXPECT_EQ(va[i].value, vb[i].value) << i;
      } else {
        EXPECT_NEAR(va[i].value, vb[i].value, 2.0 * std::max(va[i].uncertainty, vb[i].uncertainty))
            << i;
      }
    }
    std::ifstream in(b / "tree.json");
    const auto frame = nlohmann::json::parse(in).at("frame");
    const auto axis = frame.at("axes").at(2);
    const Vec3 z(axis.at(0).get<double>(), axis.at(1).get<double>(), axis.at(2).get<double>());
    EXPECT_GT(std::abs(z.dot(r.col(2))), 1.0 - 1e-6);  // the parts' z is the world's z, turned
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace csgvox
