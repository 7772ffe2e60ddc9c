// The designed tree in tree.json (frame, units, parameters, patterns beside
// the explicit primitives), in tree.txt (named patterns) and report.json's
// design section; render's round trip through tree.json.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "design/designed_tree.h"
#include "design/part_frame.h"
#include "io/design_json.h"
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

}  // namespace
}  // namespace csgvox
