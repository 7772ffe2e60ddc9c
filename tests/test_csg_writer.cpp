// tree.csg: OpenSCAD's flattened CSG, read back by csgvox's own reader into
// the same solid, for every bundled part and random trees with complements;
// the parts FreeCAD relies on ($fn = 0 for exact solids, rotations as
// rotations); the reader's errors.

#include <gtest/gtest.h>

#include <sstream>

#include "core/export_extent.h"
#include "io/csg_reader.h"
#include "io/csg_writer.h"
#include "io/errors.h"
#include "io/tree_json.h"
#include "io/tree_names.h"
#include "part_list.h"
#include "solid_sampling.h"
#include "temp_dir_test.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

std::string csgText(const CsgTree& tree) {
  std::ostringstream out;
  writeCsg(out, tree);
  return out.str();
}

CsgTree roundTrip(const CsgTree& tree) {
  std::istringstream in(csgText(tree));
  return readCsg(in);
}

class CsgFile : public test::TempDirTest {};

TEST_F(CsgFile, EveryBundledPartReadsBackAsTheSameSolid) {
  for (const std::string& part : test::partNames()) {
    SCOPED_TRACE(part);
    const CsgTree tree = readTreeJson(test::dataDir() / part / "tree.json");
    const auto path = dir_ / (part + ".csg");
    writeCsg(path, tree);
    const CsgTree back = readCsg(path);
    EXPECT_EQ(back.primitiveCount(), tree.primitiveCount());
    const Aabb extent = exportExtent(tree);
    const double iou = test::stratifiedIou(tree, back, extent.grown(0.02 * extent.diagonal()));
    EXPECT_GE(iou, 0.999);
  }
}

TEST_F(CsgFile, RandomTreesWithComplementsReadBackAsTheSameSolid) {
  test::Rng rng(5);
  for (int i = 0; i < 20; ++i) {
    const CsgTree tree = test::randomTree(rng, 2 + i % 5);
    const CsgTree back = roundTrip(tree);
    const Aabb extent = exportExtent(tree);
    EXPECT_GE(test::stratifiedIou(tree, back, extent, 40), 0.999) << i;
  }
}

TEST(CsgFormat, WritesExactSolidsThatFreeCadTurnsIntoPartFeatures) {
  const CsgTree plate =
      CsgTree::leaf(Box{Vec3(0, 0, 2.5), Mat3::Identity(), Vec3(40, 30, 2.5)}, "plate");
  const CsgTree hole = CsgTree::leaf(Cylinder{Vec3(30, 20, 2.5), Vec3::UnitZ(), 4, 7}, "hole");
  const CsgTree ring = CsgTree::leaf(Torus{Vec3(0, 0, 5), Vec3::UnitX(), 10, 2}, "ring");
  const CsgTree tree = CsgTree::subtract({CsgTree::unite({plate, ring}), hole});
  const std::string text = csgText(tree);
  EXPECT_NE(text.find("difference() {\n  union() {"), std::string::npos) << text;
  EXPECT_NE(text.find("multmatrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2.5], [0, 0, 0, 1]]) {\n"
                      "      cube(size = [80, 60, 5], center = true);  // plate"),
            std::string::npos)
      << text;
  // The hole cuts: it is written larger by the overcut (1e-6 of the part's
  // diagonal) on every side, as in tree.scad, so that FreeCAD cuts the faces
  // it ends on; what adds material is written as it is.
  const double m = 1e-6 * exportExtent(tree).diagonal();
  EXPECT_NE(text.find("cylinder($fn = 0, $fa = 12, $fs = 2, h = " + formatNumber(7 + 2 * m) +
                      ", r1 = " + formatNumber(4 + m) + ", r2 = " + formatNumber(4 + m) +
                      ", center = true);  // hole"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("rotate_extrude(angle = 360, convexity = 2, $fn = 0"), std::string::npos);
  EXPECT_NE(text.find("circle($fn = 0, $fa = 12, $fs = 2, r = 2);"), std::string::npos);
  CsgOptions exact;
  exact.overcut = 0.0;
  std::ostringstream out;
  writeCsg(out, tree, exact);
  EXPECT_NE(out.str().find("cylinder($fn = 0, $fa = 12, $fs = 2, h = 7, r1 = 4, r2 = 4, center = "
                           "true);  // hole"),
            std::string::npos)
      << out.str();
}

TEST(CsgFormat, HalfSpacesBecomeCubesWhoseTopFaceIsThePlane) {
  const CsgTree box = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3::Ones()}, "b");
  const CsgTree cut = CsgTree::leaf(HalfSpace{Vec3(1, 1, 0).normalized(), 0.25}, "cut");
  const CsgTree tree = CsgTree::intersect({box, cut});
  const CsgTree back = roundTrip(tree);
  ASSERT_EQ(back.leaves().size(), 2u);
  const Box* standIn = back.leaves()[1]->primitive.as<Box>();
  ASSERT_NE(standIn, nullptr);
  // The cube's top face lies in the plane and it covers the part.
  test::expectNear(standIn->axes.col(2), Vec3(1, 1, 0).normalized(), 1e-12);
  EXPECT_NEAR(standIn->center.dot(Vec3(1, 1, 0).normalized()) + standIn->halfSize.z(), 0.25, 1e-9);
  EXPECT_GE(standIn->halfSize.minCoeff(), 2 * std::sqrt(3.0) - 1e-9);  // the diagonal
  EXPECT_GE(test::stratifiedIou(tree, back, exportExtent(tree).grown(0.5), 40), 0.999);
}

// A half-space's cube covers everything the half-space is combined with,
// not the part only: a cylinder of radius 10 D centred 5 D away from a block
// of diagonal D, wholly under a plane, leaves nothing (a slab of it outside
// the cube stayed, on a scanned plate of bosses), and one the plane crosses
// leaves its far piece.
TEST(CsgFormat, HalfSpaceCubesCoverPrimitivesReachingFarOutsideThePart) {
  const CsgTree block = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(5, 4, 3)}, "block");
  const double d = 2.0 * Vec3(5, 4, 3).norm();
  const CsgTree cylinder =
      CsgTree::leaf(Cylinder{Vec3(5 * d, 0, 0), Vec3::UnitZ(), 10 * d, 4}, "cylinder");
  for (const CsgTree& cut :
       {CsgTree::subtract({cylinder, CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 2.5})}),
        CsgTree::subtract({cylinder, CsgTree::leaf(HalfSpace{Vec3::UnitX(), 13 * d})}),
        CsgTree::intersect({cylinder, CsgTree::leaf(HalfSpace{-Vec3::UnitZ(), -2.5})}),
        CsgTree::intersect({cylinder, CsgTree::leaf(HalfSpace{-Vec3::UnitX(), -13 * d})})}) {
    const CsgTree tree = CsgTree::unite({block, cut});
    const CsgTree back = roundTrip(tree);
    const Aabb all = cylinder.bounds();
    EXPECT_GE(test::stratifiedIou(tree, back, all, 60), 0.999);
    // Written alone (when its bounds are not empty), it is cut by a cube
    // covering the cylinder, not the part's sliver.
    if (cut.bounds().isEmpty()) continue;
    EXPECT_GE(test::stratifiedIou(cut, roundTrip(cut), all, 60), 0.999);
  }
}

TEST(CsgReader, ReadsOpenScadsOwnSpellings) {
  std::istringstream in(
      "group() {\n  difference() {\n    cube(size = [2, 2, 2], center = false);\n"
      "    /* a hole */ multmatrix([[1,0,0,1],[0,1,0,1],[0,0,1,-1],[0,0,0,1]]) {\n"
      "      cylinder($fn = 24, $fa = 12, $fs = 2, h = 4, r1 = 0.5, r2 = 0.5, center = false);\n"
      "    }\n    sphere(r = 0.25);\n  }\n}\n");
  const CsgTree t = readCsg(in);
  EXPECT_TRUE(t.contains(Vec3(0.2, 1.8, 1)));
  EXPECT_FALSE(t.contains(Vec3(1, 1, 1)));        // the hole, centred at (1, 1)
  EXPECT_FALSE(t.contains(Vec3(0.1, 0.1, 0.1)));  // the sphere at the origin
  EXPECT_FALSE(t.contains(Vec3(2.5, 1, 1)));
}

TEST(CsgReader, ErrorsNameTheSourceAndLine) {
  const auto message = [](const std::string& text) {
    std::istringstream in(text);
    try {
      readCsg(in, "t.csg");
    } catch (const ParseError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("union() {\n  polyhedron(points = [], faces = []);\n}\n"),
            "t.csg: line 2: unsupported statement 'polyhedron'");
  EXPECT_EQ(message("multmatrix([[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]) { cube(1); }"),
            "t.csg: line 1: multmatrix: only rotations and translations are supported");
  EXPECT_EQ(message("union() {\n cube(1);\n"), "t.csg: line 3: missing '}'");
  EXPECT_EQ(message("cylinder(h = 1);"), "t.csg: line 1: cylinder: needs a number r1");
  EXPECT_EQ(message("// nothing\n"), "t.csg: holds no solid");
  EXPECT_EQ(message("cube(size = [1, 1, nan]);"), "t.csg: line 1: a number is not finite");
}

}  // namespace
}  // namespace csgvox
