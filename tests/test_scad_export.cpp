// The OpenSCAD export: its text, and (when openscad is installed) that
// OpenSCAD renders it to the same solid as the tree and as csgvox's mesh.

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "io/mesh_files.h"
#include "io/scad_export.h"
#include "io/tree_json.h"
#include "io/tree_names.h"
#include "mesh/mesh_export.h"
#include "mesh/mesh_solid.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

std::string scadText(const CsgTree& tree) {
  std::ostringstream s;
  writeScad(s, tree);
  return s.str();
}

CsgTree plate() {
  return CsgTree::subtract(
      {CsgTree::leaf(Box{Vec3(0, 0, 2.5), Mat3::Identity(), Vec3(40, 30, 2.5)}, "plate"),
       CsgTree::leaf(Cylinder{Vec3(30, 20, 2.5), Vec3::UnitZ(), 4, 7}, "hole"),
       CsgTree::leaf(Cylinder{Vec3(-30, 20, 2.5), Vec3::UnitZ(), 4, 7}, "hole")});
}

TEST(ScadExport, OneNamedModulePerPrimitiveThenTheExpression) {
  const std::string s = scadText(plate());
  EXPECT_NE(s.find("module plate() translate([0, 0, 2.5]) cube([80, 60, 5], center = true);\n"),
            std::string::npos)
      << s;
  EXPECT_NE(s.find("module hole() translate([30, 20, 2.5]) cylinder(h = 7, r = 4, center = true);"),
            std::string::npos)
      << s;
  // A repeated name is made unique.
  EXPECT_NE(s.find("module hole_1() translate([-30, 20, 2.5])"), std::string::npos) << s;
  EXPECT_NE(s.find("difference() {\n  plate();\n  hole();\n  hole_1();\n}\n"), std::string::npos)
      << s;
}

TEST(ScadExport, AxisAlignedBoxesWithPermutedAxesNeedNoRotation) {
  Box b{Vec3(1, 2, 3), Mat3::Identity(), Vec3(1, 2, 3)};
  b.axes.col(0) = Vec3(0, 1, 0);
  b.axes.col(1) = Vec3(-1, 0, 0);
  b.halfSize = Vec3(2, 1, 3);  // same solid as the identity box with (1, 2, 3)
  const std::string s = scadText(CsgTree::leaf(b, "b"));
  EXPECT_NE(s.find("module b() translate([1, 2, 3]) cube([2, 4, 6], center = true);"),
            std::string::npos)
      << s;
}

TEST(ScadExport, RejectsTreesWithoutExtent) {
  std::ostringstream s;
  EXPECT_THROW(writeScad(s, CsgTree()), std::invalid_argument);
  EXPECT_THROW(writeScad(s, CsgTree::leaf(HalfSpace{})), std::invalid_argument);
}

TEST(ScadExport, ModuleNamesNeverTakeOpenScadNames) {
  for (const char* word : {"difference", "module", "cylinder", "union", "cube", "sphere",
                           "function", "if", "for", "let", "echo", "children", "rotate_extrude",
                           "circle", "translate", "true", "undef", "assert", "each"}) {
    EXPECT_TRUE(isOpenScadReserved(word)) << word;
  }
  for (const char* word : {"plate", "hole", "cube1", "cylinder2", "Difference", "box"}) {
    EXPECT_FALSE(isOpenScadReserved(word)) << word;
  }
  const CsgTree t =
      CsgTree::subtract({CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2, 2, 2)}, "cube"),
                         CsgTree::leaf(Cylinder{Vec3::Zero(), Vec3::UnitZ(), 1, 5}, "difference"),
                         CsgTree::leaf(Sphere{Vec3(2, 2, 2), 1}, "module"),
                         CsgTree::leaf(Sphere{Vec3(-2, 2, 2), 1}, "difference_1")});
  const std::string s = scadText(t);
  EXPECT_NE(s.find("module cube_1() "), std::string::npos) << s;
  EXPECT_NE(s.find("module difference_2() "), std::string::npos) << s;  // difference_1 is taken
  EXPECT_NE(s.find("module module_1() "), std::string::npos) << s;
  EXPECT_NE(s.find("module difference_1() "), std::string::npos) << s;
  EXPECT_EQ(s.find("module cube() "), std::string::npos) << s;
}

// ---- OpenSCAD round trip ----------------------------------------------------

bool haveOpenScad() { return std::system("openscad --version > /dev/null 2>&1") == 0; }

class ScadRendersTheSameSolid : public ::testing::TestWithParam<std::string> {};

TEST_P(ScadRendersTheSameSolid, AsTheTreeAndItsMesh) {
  if (!haveOpenScad()) {
    GTEST_SKIP() << "openscad is not installed (scripts/install-deps.sh installs it); "
                    "skipping the OpenSCAD round trip";
  }
  const std::string part = GetParam();
  const CsgTree tree = readTreeJson(test::dataDir() / part / "tree.json");
  const fs::path dir = test::freshTempDir("scad-" + part);
  writeScad(dir / "tree.scad", tree);
  const std::string cmd = "openscad -o '" + (dir / "openscad.stl").string() + "' '" +
                          (dir / "tree.scad").string() + "' > '" + (dir / "log.txt").string() +
                          "' 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0)
      << "openscad failed on " << part << ", see " << (dir / "log.txt");
  const TriangleMesh scadMesh = readMesh(dir / "openscad.stl");
  const Aabb box = tree.bounds();
  const double voxel = box.diagonal() / 400.0;
  const MeshSolid scadSolid(scadMesh, voxel);
  const MeshSolid renderSolid(meshTree(tree), voxel);
  const auto inScad = [&](const Vec3& p) { return scadSolid.contains(p); };
  const double vsTree = test::sampledIou(
      box, inScad, [&](const Vec3& p) { return tree.contains(p); }, 200000, 1);
  const double vsRender = test::sampledIou(
      box, inScad, [&](const Vec3& p) { return renderSolid.contains(p); }, 200000, 2);
  EXPECT_GE(vsTree, 0.99) << part;
  EXPECT_GE(vsRender, 0.99) << part;
  RecordProperty("iou_vs_tree", std::to_string(vsTree));
  RecordProperty("iou_vs_render", std::to_string(vsRender));
  fs::remove_all(dir);
}

// Renders `tree` with OpenSCAD; returns the solid's IoU against the tree.
double openScadIouAgainstTree(const CsgTree& tree, const std::string& name) {
  const fs::path dir = test::freshTempDir("scad-" + name);
  writeScad(dir / "tree.scad", tree);
  const std::string cmd = "openscad -o '" + (dir / "openscad.stl").string() + "' '" +
                          (dir / "tree.scad").string() + "' > '" + (dir / "log.txt").string() +
                          "' 2>&1";
  if (std::system(cmd.c_str()) != 0) {
    ADD_FAILURE() << "openscad failed on " << name << ", see " << (dir / "log.txt");
    return 0.0;
  }
  const Aabb box = tree.bounds();
  const MeshSolid scadSolid(readMesh(dir / "openscad.stl"), box.diagonal() / 400.0);
  const double iou = test::sampledIou(
      box, [&](const Vec3& p) { return scadSolid.contains(p); },
      [&](const Vec3& p) { return tree.contains(p); }, 200000, 3);
  fs::remove_all(dir);
  return iou;
}

TEST(ScadRendersTheSameSolidWith, PrimitivesNamedAfterOpenScadBuiltIns) {
  if (!haveOpenScad()) GTEST_SKIP() << "openscad is not installed";
  // With these names taken as module names, OpenSCAD would reject the file
  // ("module", "for") or call the leaves' modules in place of its built-ins
  // (a "cylinder" module made of a cylinder recurses; "cube" and "sphere"
  // replace the shapes the other modules use).
  const CsgTree t = CsgTree::subtract(
      {CsgTree::unite({CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(4, 3, 1)}, "cube"),
                       CsgTree::leaf(Cylinder{Vec3(0, 0, 1.5), Vec3::UnitZ(), 1.5, 2}, "union")}),
       CsgTree::leaf(Cylinder{Vec3(2.5, 0, 0), Vec3::UnitZ(), 0.5, 3}, "cylinder"),
       CsgTree::leaf(Sphere{Vec3(-2.5, 0, 1), 0.8}, "sphere"),
       CsgTree::leaf(Cylinder{Vec3(0, 2, 0), Vec3::UnitZ(), 0.4, 3}, "difference"),
       CsgTree::leaf(Cylinder{Vec3(0, -2, 0), Vec3::UnitZ(), 0.4, 3}, "module"),
       CsgTree::leaf(Box{Vec3(-2.5, -2.5, 0), Mat3::Identity(), Vec3(0.3, 0.3, 2)}, "for")});
  EXPECT_GE(openScadIouAgainstTree(t, "reserved-names"), 0.99);
}

INSTANTIATE_TEST_SUITE_P(BundledParts, ScadRendersTheSameSolid,
                         ::testing::ValuesIn(test::partNames()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace csgvox
