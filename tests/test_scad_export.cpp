// The OpenSCAD export: its text, and (when openscad is installed) that
// OpenSCAD renders it to the same solid as the tree and as csgvox's mesh.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

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

std::string scadText(const CsgTree& tree, const ScadOptions& options = {}) {
  std::ostringstream s;
  writeScad(s, tree, options);
  return s.str();
}

ScadOptions noOvercut() {
  ScadOptions o;
  o.overcut = 0.0;
  return o;
}

CsgTree plate() {
  return CsgTree::subtract(
      {CsgTree::leaf(Box{Vec3(0, 0, 2.5), Mat3::Identity(), Vec3(40, 30, 2.5)}, "plate"),
       CsgTree::leaf(Cylinder{Vec3(30, 20, 2.5), Vec3::UnitZ(), 4, 7}, "hole"),
       CsgTree::leaf(Cylinder{Vec3(-30, 20, 2.5), Vec3::UnitZ(), 4, 7}, "hole")});
}

TEST(ScadExport, OneNamedModulePerPrimitiveThenTheExpression) {
  const std::string s = scadText(plate(), noOvercut());
  EXPECT_NE(s.find("module plate() translate([0, 0, 2.5]) cube([80, 60, 5], center = true);\n"),
            std::string::npos)
      << s;
  EXPECT_NE(
      s.find("module hole() translate([30, 20, 2.5]) cylinder(h = 7, r = 4, center = true, $fn = "),
      std::string::npos)
      << s;
  // A repeated name is made unique.
  EXPECT_NE(s.find("module hole_1() translate([-30, 20, 2.5])"), std::string::npos) << s;
  EXPECT_NE(s.find("difference() {\n  plate();\n  hole();\n  hole_1();\n}\n"), std::string::npos)
      << s;
}

// What removes material is written larger by the overcut (a fraction of
// the part's diagonal) on every side; what adds material is written as it
// is; a primitive that does both gets a second, grown module for its cuts.
TEST(ScadExport, CuttersAreWrittenGrownByTheOvercut) {
  const double m = 1e-6 * plate().bounds().diagonal();
  const std::string s = scadText(plate());
  EXPECT_NE(s.find("module plate() translate([0, 0, 2.5]) cube([80, 60, 5], center = true);\n"),
            std::string::npos)
      << s;
  EXPECT_NE(
      s.find("module hole() translate([30, 20, 2.5]) cylinder(h = " + formatNumber(7 + 2 * m) +
             ", r = " + formatNumber(4 + m) + ", center = true, $fn = "),
      std::string::npos)
      << s;
  EXPECT_NE(s.find("difference() {\n  plate();\n  hole();\n  hole_1();\n}\n"), std::string::npos)
      << s;

  // A cutter of a cutter adds material: a box less a ring (a disc less a
  // smaller disc) keeps the inner disc.
  const CsgTree disc = CsgTree::leaf(Cylinder{Vec3::Zero(), Vec3::UnitZ(), 1, 4}, "disc");
  const CsgTree ring = CsgTree::subtract(
      {CsgTree::leaf(Cylinder{Vec3::Zero(), Vec3::UnitZ(), 2, 4}, "outer"), disc});
  const CsgTree t = CsgTree::unite(
      {CsgTree::subtract(
           {CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(3, 3, 1)}, "block"), ring}),
       CsgTree::subtract(
           {CsgTree::leaf(Box{Vec3(0, 0, 3), Mat3::Identity(), Vec3(3, 3, 1)}, "lid"), disc})});
  const double d = 1e-6 * t.bounds().diagonal();
  const std::string r = scadText(t);
  EXPECT_NE(r.find("module outer() cylinder(h = " + formatNumber(4 + 2 * d) +
                   ", r = " + formatNumber(2 + d) + ", center = true, $fn = "),
            std::string::npos)
      << r;
  // The disc adds inside the ring and removes from the lid: two modules.
  EXPECT_NE(r.find("module disc() cylinder(h = 4, r = 1, center = true, $fn = "), std::string::npos)
      << r;
  EXPECT_NE(r.find("module disc_cut() cylinder(h = " + formatNumber(4 + 2 * d) +
                   ", r = " + formatNumber(1 + d) + ", center = true, $fn = "),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("difference() {\n      outer();\n      disc();\n    }"), std::string::npos) << r;
  EXPECT_NE(r.find("difference() {\n    lid();\n    disc_cut();\n  }"), std::string::npos) << r;
  // What a complement holds removes material too.
  const CsgTree c =
      CsgTree::intersect({CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(3, 3, 1)}, "slab"),
                          CsgTree::complement(CsgTree::leaf(Sphere{Vec3::Zero(), 1}, "ball"))});
  const double e = 1e-6 * c.bounds().diagonal();
  const std::string cs = scadText(c);
  EXPECT_NE(cs.find("module ball() sphere(r = " + formatNumber(1 + e) + ", $fn = "),
            std::string::npos)
      << cs;
  EXPECT_NE(cs.find("module slab() cube([6, 6, 2], center = true);"), std::string::npos) << cs;
  // With no overcut, nothing is grown and no second module is needed.
  const std::string z = scadText(t, noOvercut());
  EXPECT_NE(z.find("module outer() cylinder(h = 4, r = 2, center = true, $fn = "),
            std::string::npos)
      << z;
  EXPECT_EQ(z.find("disc_cut();"), std::string::npos) << z;
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

// A turned part: a shaft of nine sections on one axis, eleven tori
// rounding its shoulders and cutting its grooves, and nine holes, bosses
// and cones: 29 primitives.
CsgTree turnedPart() {
  std::vector<CsgTree> sections, cuts;
  double z = 0.0;
  const double radii[] = {30, 26, 22, 18, 22, 26, 20, 15, 12};
  for (int i = 0; i < 9; ++i) {
    sections.push_back(CsgTree::leaf(Cylinder{Vec3(0, 0, z + 7.5), Vec3::UnitZ(), radii[i], 15}));
    z += 15.0;
  }
  for (int i = 0; i < 11; ++i) {
    const double r = radii[i % 9];
    cuts.push_back(
        CsgTree::leaf(Torus{Vec3(0, 0, 5.0 + 12.0 * i), Vec3::UnitZ(), r, 1.5 + 0.2 * i}));
  }
  for (int i = 0; i < 5; ++i) {
    cuts.push_back(CsgTree::leaf(Cylinder{Vec3(12 * std::cos(1.2 * i), 12 * std::sin(1.2 * i), 7.5),
                                          Vec3::UnitZ(), 2.5, 16}));
  }
  cuts.push_back(CsgTree::leaf(Cone{Vec3(0, 0, 130), Vec3::UnitZ(), 3, 8, 10}));
  cuts.push_back(CsgTree::leaf(Sphere{Vec3(0, 0, 0), 6}));
  cuts.push_back(CsgTree::leaf(Box{Vec3(0, 28, 40), Mat3::Identity(), Vec3(3, 4, 5)}));
  cuts.push_back(CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 132}));
  std::vector<CsgTree> operands = {CsgTree::unite(sections)};
  operands.insert(operands.end(), cuts.begin(), cuts.end() - 1);
  return CsgTree::intersect({CsgTree::subtract(operands), cuts.back()});
}

// The segment counts a tree.scad gives its curved primitives, and the
// facets they make: a cylinder's or cone's side n, a sphere's n²/2, a
// torus's sweep times its tube.
struct Segments {
  int largest = 0;
  long facets = 0;
  int curved = 0;
};

Segments segmentsOf(const std::string& scad) {
  Segments out;
  std::istringstream in(scad);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("module ", 0) != 0) continue;
    std::vector<int> counts;
    for (std::size_t at = line.find("segments("); at != std::string::npos;
         at = line.find("segments(", at + 1)) {
      counts.push_back(std::stoi(line.substr(at + 9)));
    }
    if (counts.empty()) continue;
    ++out.curved;
    for (int n : counts) out.largest = std::max(out.largest, n);
    if (line.find("rotate_extrude") != std::string::npos) {
      out.facets += long(counts.at(0)) * counts.at(1);
    } else if (line.find("sphere(") != std::string::npos) {
      out.facets += long(counts.at(0)) * counts.at(0) / 2;
    } else {
      out.facets += counts.at(0);
    }
  }
  return out;
}

// Each curve's segments follow its size (a hole gets fewer than the shaft
// it is cut in), tori are coarse, and the whole stays within a budget that
// OpenSCAD 2021 renders in seconds: with $fn = 64 on every curve, the
// eleven tori alone made 45 000 facets and the render took minutes.
TEST(ScadExport, SegmentCountsFollowEachPrimitivesSize) {
  const CsgTree part = turnedPart();
  ASSERT_EQ(part.primitiveCount(), 29u);
  const std::string s = scadText(part);
  EXPECT_NE(s.find("\ndetail = 1;\nfunction segments(n) = max(3, round(n * detail));\n"),
            std::string::npos)
      << s;
  const Segments seg = segmentsOf(s);
  EXPECT_EQ(seg.curved, 27);  // all but the box and the half-space
  EXPECT_LE(seg.largest, ScadOptions{}.maxSegments);
  EXPECT_GE(seg.largest, 64);  // the shaft's largest section stays round
  EXPECT_LE(seg.facets, 10000);
  RecordProperty("facets", std::to_string(seg.facets));
  std::printf("[ segments ] largest %d, %ld facets\n", seg.largest, seg.facets);
  // A hole of radius 2.5 (16 long, and grown: it cuts) gets fewer segments than
  // the section of radius 30.
  const auto countOf = [&](const std::string& what) {
    const std::size_t at = s.find(what);
    EXPECT_NE(at, std::string::npos) << what;
    return std::stoi(s.substr(s.find("segments(", at) + 9));
  };
  EXPECT_LT(countOf("cylinder(h = 16"), countOf("cylinder(h = 15, r = 30"));
  // A fixed count, when asked for, is every curve's.
  ScadOptions fixed;
  fixed.facets = 20;
  const Segments f = segmentsOf(scadText(part, fixed));
  EXPECT_EQ(f.largest, 20);
  EXPECT_EQ(f.facets, 20L * 15 + 11L * 20 * 20 + 20 * 20 / 2);
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

// A flange's plate and three of its bolt holes as fitted to the noisy scan
// data/flange/scan_noisy.ply: two holes end on both of the plate's faces,
// one on its top face, to the last bits of the fit. Written as they are,
// OpenSCAD's exact booleans left a film of a face across a hole (an extra
// volume in its log, and IoU 0.989 against the mesh of the main job's
// tree); the overcut opens them.
TEST(ScadRendersTheSameSolidWith, HolesThatEndOnTheFacesTheyGoThrough) {
  if (!haveOpenScad()) GTEST_SKIP() << "openscad is not installed";
  const Vec3 up(-0.0002312274085214225, 7.324411988004418e-05, 0.9999999705845918);
  const double r = 4.931239233598219;
  const CsgTree t = CsgTree::subtract(
      {CsgTree::leaf(Cylinder{Vec3(-0.020803035320374887, 0.004036445965827896, 5.968504581766771),
                              up, 50.01573130326098, 12.008915724373828},
                     "plate"),
       CsgTree::leaf(Cylinder{Vec3(32.99509836910849, -19.02802555797279, 5.977532749985064), up, r,
                              12.008915724373828},
                     "hole"),
       CsgTree::leaf(Cylinder{Vec3(-32.930931076999336, 19.07464027877664, 5.959498048287339), up,
                              r, 12.008915724373828},
                     "hole"),
       CsgTree::leaf(Cylinder{Vec3(-0.07631421648536403, 38.039799463441206, 6.873603059170291),
                              -up, r, 13.824710089318678},
                     "hole")});
  EXPECT_GE(openScadIouAgainstTree(t, "holes-on-faces"), 0.99);
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
