// tree.scad for editing: the parameter block, role-named modules, pattern
// loops, and what a designer does with it — edit one parameter, render.

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "design/designed_tree.h"
#include "io/design_scad.h"
#include "io/mesh_files.h"
#include "io/scad_export.h"
#include "io/tree_json.h"
#include "mesh/mesh_solid.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

CsgTree part(const std::string& name) { return readTreeJson(test::dataDir() / name / "tree.json"); }

std::string designedScad(const DesignedTree& d) {
  std::ostringstream out;
  writeDesignedScad(out, d);
  return out.str();
}

bool haveOpenScad() { return std::system("openscad --version > /dev/null 2>&1") == 0; }

// Renders `program` with OpenSCAD into an STL file and reads it.
TriangleMesh render(const std::string& program, const fs::path& dir, const std::string& name) {
  const fs::path scad = dir / (name + ".scad"), stl = dir / (name + ".stl");
  std::ofstream(scad) << program;
  const std::string cmd = "timeout 300 openscad -o '" + stl.string() + "' '" + scad.string() +
                          "' > '" + (dir / (name + ".log")).string() + "' 2>&1";
  if (std::system(cmd.c_str()) != 0) {
    ADD_FAILURE() << "openscad failed, see " << (dir / (name + ".log"));
    return {};
  }
  return readMesh(stl);
}

TEST(DesignScad, FlangeHasAParameterBlockAndOneLoop) {
  const DesignedTree d = designTree(part("flange"));
  const std::string scad = designedScad(d);
  EXPECT_NE(scad.find("\nbolt_circle_r = 38;"), std::string::npos);
  EXPECT_NE(scad.find("\nbolt_circle_count = 6;"), std::string::npos);
  EXPECT_NE(scad.find("\nhub_r = 25;"), std::string::npos);
  EXPECT_EQ(std::count(scad.begin(), scad.end(), '\n') > 0, true);
  // One loop; one hole module for the six holes.
  const std::regex loop(R"(for \(i = \[0 : bolt_circle_count - 1\]\))");
  EXPECT_EQ(
      std::distance(std::sregex_iterator(scad.begin(), scad.end(), loop), std::sregex_iterator()),
      1);
  const std::regex holes(R"(module hole_\d+\(g = 0\))");
  EXPECT_EQ(
      std::distance(std::sregex_iterator(scad.begin(), scad.end(), holes), std::sregex_iterator()),
      1);
  const std::regex modules(R"(module (plate|hub|bore|fillet)\w*\(g = 0\))");
  EXPECT_GE(std::distance(std::sregex_iterator(scad.begin(), scad.end(), modules),
                          std::sregex_iterator()),
            4);
}

// Of the numbers in the body, most are parameters or expressions on every
// bundled part; the fitted export's are all literals.
TEST(DesignScad, BodyNumbersAreParameters) {
  for (const std::string& name : test::partNames()) {
    SCOPED_TRACE(name);
    const CsgTree tree = part(name);
    const ScadLiteralCount c = countScadLiterals(designedScad(designTree(tree)));
    ASSERT_GT(c.numbers, 0);
    EXPECT_GE(double(c.parameters) / c.numbers, 0.7) << c.parameters << " of " << c.numbers;
    std::ostringstream raw;
    writeScad(raw, tree);
    EXPECT_EQ(countScadLiterals(raw.str()).parameters, 0);
  }
}

// The issue's edit: move the bolt circle out in tree.scad, render it; all six
// holes move, the volume stays.
TEST(DesignScad, EditingTheBoltCircleMovesEverySixHoles) {
  if (!haveOpenScad()) GTEST_SKIP() << "openscad is not installed";
  const fs::path dir = test::freshTempDir("design-scad-edit");
  const DesignedTree d = designTree(part("flange"));
  ASSERT_EQ(d.patterns.size(), 1u);
  const DesignedPattern& p = d.patterns.front();
  const std::string name = p.radius.text(d.parameters);
  const std::string scad = designedScad(d);
  const std::string line = "\n" + name + " = 38;";
  ASSERT_NE(scad.find(line), std::string::npos);
  std::string edited = scad;
  edited.replace(edited.find(line), line.size(), "\n" + name + " = 44;");
  const TriangleMesh before = render(scad, dir, "before"), after = render(edited, dir, "after");
  ASSERT_FALSE(before.triangles.empty());
  ASSERT_FALSE(after.triangles.empty());
  EXPECT_NEAR(after.volume(), before.volume(), 1e-3 * before.volume());
  const double voxel = before.bounds().diagonal() / 400.0;
  const MeshSolid a(before, voxel), b(after, voxel);
  for (int m : p.members) {
    const Cylinder hole = *d.localPrimitive(m).as<Cylinder>();
    Vec3 was = hole.center;
    was.z() = 6.0;  // mid-plate
    const Vec3 centre(p.centerX.value(d.parameters), p.centerY.value(d.parameters), 6.0);
    const Vec3 now = centre + (was - centre) * (44.0 / 38.0);
    EXPECT_FALSE(a.contains(d.frame.toWorld(was)));
    EXPECT_TRUE(a.contains(d.frame.toWorld(now)));
    EXPECT_TRUE(b.contains(d.frame.toWorld(was)));
    EXPECT_FALSE(b.contains(d.frame.toWorld(now)));
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace csgvox
