// The GP baseline's files: .fit primitives and expressions read into trees
// whose values are the baseline's operation semantics (union = max,
// intersection = min, subtraction = min(A, -B), negation = -A) on the leaves'
// distances; every bad input is one error line naming the file; the
// import-gp command on both bundled samples.

#include <gtest/gtest.h>

#include <array>
#include <cctype>
#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_helpers.h"
#include "io/errors.h"
#include "io/gp_files.h"
#include "io/tree_json.h"
#include "temp_dir_test.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::randomPoint;
using test::Rng;

const fs::path kGpDir = fs::path(CSGVOX_DATA_DIR) / "gp-baseline";

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// ---------------------------------------------------------------------------
// An independent reference: the .fit lines' values and the expression's
// semantics, straight from the README, evaluated by recursive descent.

struct FitLine {
  std::string type;
  std::vector<double> v;
};

std::vector<FitLine> fitLines(const fs::path& p) {
  std::vector<FitLine> lines;
  std::istringstream in(readText(p));
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    FitLine f;
    words >> f.type;
    for (double x; words >> x;) f.v.push_back(x);
    lines.push_back(f);
  }
  return lines;
}

// f >= 0 inside, for the planes and cylinders of the samples (unit normals
// and axes in the files).
double fitValue(const FitLine& f, const Vec3& x) {
  const Vec3 a(f.v[0], f.v[1], f.v[2]);
  if (f.type == "plane") return f.v[3] - a.dot(x);
  if (f.type == "cylinder") {
    const Vec3 d = x - Vec3(f.v[3], f.v[4], f.v[5]);
    return f.v[6] - (d - d.dot(a) * a).norm();
  }
  ADD_FAILURE() << "reference evaluator: unsupported type " << f.type;
  return 0.0;
}

class ReferenceExpression {
 public:
  ReferenceExpression(std::string text, const std::vector<FitLine>& fit)
      : text_(std::move(text)), fit_(fit) {}

  double value(const Vec3& x) {
    pos_ = 0;
    return node(x);
  }

 private:
  double node(const Vec3& x) {
    std::string word;
    while (pos_ < text_.size() && std::isalnum(static_cast<unsigned char>(text_[pos_]))) {
      word += text_[pos_++];
    }
    if (pos_ < text_.size() && text_[pos_] == '[') {
      ++pos_;
      const double a = node(x);
      double b = 0.0;
      if (text_[pos_] == ',') {
        ++pos_;
        b = node(x);
      }
      ++pos_;  // ']'
      if (word == "union") return std::max(a, b);
      if (word == "intersection") return std::min(a, b);
      if (word == "subtraction") return std::min(a, -b);
      if (word == "negation") return -a;
      ADD_FAILURE() << "reference evaluator: unknown operation " << word;
      return 0.0;
    }
    const std::size_t digits = word.find_first_of("0123456789");
    const FitLine& f = fit_.at(std::stoul(word.substr(digits)));
    EXPECT_EQ(f.type, word.substr(0, digits));
    return fitValue(f, x);
  }

  std::string text_;
  const std::vector<FitLine>& fit_;
  std::size_t pos_ = 0;
};

double boxValue(const Aabb& box, const Vec3& p) {
  Box b;
  b.center = box.center();
  b.halfSize = 0.5 * box.size();
  return Primitive(b).value(p);
}

std::vector<std::string> leafNames(const CsgTree& tree) {
  std::vector<std::string> names;
  for (const Node* leaf : tree.leaves()) names.push_back(leaf->name);
  return names;
}

// ---------------------------------------------------------------------------
// The samples

TEST(GpFiles, CubePrimitivesAreSixPlanesWithTheFitConvention) {
  const std::vector<GpPrimitive> prims = readGpPrimitives(kGpDir / "cube.fit");
  ASSERT_EQ(prims.size(), 6u);
  for (std::size_t i = 0; i < prims.size(); ++i) {
    EXPECT_EQ(prims[i].name, "plane" + std::to_string(i));
    ASSERT_TRUE(std::holds_alternative<PlaneSurface>(prims[i].shape));
  }
  // "plane 0 0 1 -1": f = -1 - z >= 0, the solid z <= -1: normal (0,0,1), offset -1.
  const auto& p2 = std::get<PlaneSurface>(prims[2].shape);
  test::expectNear(p2.normal, Vec3::UnitZ(), 0.0);
  EXPECT_EQ(p2.offset, -1.0);
  // "plane 0 -1 -0 -1": the solid y >= 1.
  const auto& p3 = std::get<PlaneSurface>(prims[3].shape);
  test::expectNear(p3.normal, -Vec3::UnitY(), 0.0);
  EXPECT_EQ(p3.offset, -1.0);
}

TEST(GpFiles, CubeTreeHasTheBaselineSemantics) {
  const std::vector<GpPrimitive> prims = readGpPrimitives(kGpDir / "cube.fit");
  const Aabb box = gpClipBox(prims);
  const CsgTree tree = readGpExpression(kGpDir / "cube_expr.txt", prims, box);
  EXPECT_EQ(tree.primitiveCount(), 7u);
  EXPECT_EQ(tree.operationCount(), 13u);
  EXPECT_EQ(leafNames(tree), (std::vector<std::string>{"plane0", "plane4", "plane0", "plane2",
                                                       "plane1", "plane3", "plane5"}));

  // The expression written out by hand over the .fit lines' f = d - n·x.
  const std::vector<FitLine> fit = fitLines(kGpDir / "cube.fit");
  ASSERT_EQ(fit.size(), 6u);
  const auto expected = [&fit](const Vec3& x) {
    std::array<double, 6> f;
    for (int i = 0; i < 6; ++i) f[i] = fitValue(fit[i], x);
    const double inner = std::min(-f[2], -std::max(f[1], f[3]));
    const double u = std::max(std::max(f[4], -f[0]), -inner);
    return std::min(f[0], std::min(-u, -(-f[5])));
  };
  ReferenceExpression reference(readText(kGpDir / "cube_expr.txt"), fit);
  Rng rng(2016);
  int inside = 0;
  for (int i = 0; i < 5000; ++i) {
    const Vec3 p = randomPoint(rng, box);
    EXPECT_NEAR(tree.value(p), expected(p), 1e-12) << test::str(p);
    EXPECT_NEAR(reference.value(p), expected(p), 1e-12) << test::str(p);
    // The baseline's tree is the cube [-1, 1]^3.
    const bool inCube = (p.array().abs() <= 1.0).all();
    EXPECT_EQ(tree.contains(p), inCube) << test::str(p);
    inside += inCube;
  }
  EXPECT_GT(inside, 1000);
  EXPECT_LT(inside, 4500);
}

TEST(GpFiles, ImportIntersectsWithTheClipBox) {
  const GpImport imported = importGp(kGpDir / "cube.fit", kGpDir / "cube_expr.txt");
  const CsgTree& tree = imported.tree;
  ASSERT_EQ(tree.root()->kind, NodeKind::Intersection);
  ASSERT_EQ(tree.root()->children.size(), 2u);
  EXPECT_EQ(tree.root()->children[1]->name, "clip_box");
  EXPECT_TRUE(tree.bounds().isBounded());
  EXPECT_EQ(imported.primitives.size(), 6u);
  const CsgTree bare =
      readGpExpression(kGpDir / "cube_expr.txt", imported.primitives, imported.box);
  Rng rng(5);
  const Aabb around = imported.box.grown(1.0);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p = randomPoint(rng, around);
    EXPECT_EQ(tree.value(p), std::min(bare.value(p), boxValue(imported.box, p)));
  }
  // Without clipping, the expression's tree alone.
  GpImportOptions o;
  o.clipToBox = false;
  EXPECT_TRUE(
      importGp(kGpDir / "cube.fit", kGpDir / "cube_expr.txt", o).tree.structurallyEqual(bare));
  // A given box is used as it is.
  o.box = Aabb{Vec3::Constant(-3), Vec3::Constant(2)};
  o.clipToBox = true;
  const GpImport withBox = importGp(kGpDir / "cube.fit", kGpDir / "cube_expr.txt", o);
  test::expectNear(withBox.box.min, Vec3::Constant(-3), 0.0);
  test::expectNear(withBox.box.max, Vec3::Constant(2), 0.0);
}

TEST(GpFiles, PlateHolesPrimitivesAndTree) {
  const std::vector<GpPrimitive> prims = readGpPrimitives(kGpDir / "plate_holes.fit");
  ASSERT_EQ(prims.size(), 20u);
  for (std::size_t i = 0; i < prims.size(); ++i) {
    const bool cylinder = i >= 6 && i <= 9;
    EXPECT_EQ(prims[i].name, (cylinder ? "cylinder" : "plane") + std::to_string(i));
    EXPECT_EQ(std::holds_alternative<CylinderSurface>(prims[i].shape), cylinder) << i;
  }
  const auto& c6 = std::get<CylinderSurface>(prims[6].shape);
  test::expectNear(c6.axisPoint, Vec3(-38, -20, 0), 0.0);
  test::expectNear(c6.axisDir, -Vec3::UnitZ(), 0.0);
  EXPECT_NEAR(c6.radius, 5.0, 1e-6);

  // The box of the reference points holds the plate [-50,50]x[-30,30]x[0,8].
  const Aabb box = gpClipBox(prims);
  EXPECT_TRUE(box.contains(Vec3(-50, -30, 0)) && box.contains(Vec3(50, 30, 8)));
  EXPECT_LT(box.diagonal(), 1.5 * Vec3(100, 60, 8).norm());

  const CsgTree tree = readGpExpression(kGpDir / "plate_holes_expr.txt", prims, box);
  EXPECT_EQ(leafNames(tree), (std::vector<std::string>{"plane14", "plane0"}));
  EXPECT_EQ(tree.root()->kind, NodeKind::Intersection);
  const std::vector<FitLine> fit = fitLines(kGpDir / "plate_holes.fit");
  ReferenceExpression reference(readText(kGpDir / "plate_holes_expr.txt"), fit);
  Rng rng(14);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p = randomPoint(rng, box);
    EXPECT_NEAR(tree.value(p), reference.value(p), 1e-12) << test::str(p);
  }
}

// Expressions over every operation and the plate's cylinders (capped in the
// import, unbounded in the reference) agree everywhere in the clip box.
TEST(GpFiles, EveryOperationOverPlanesAndCylindersMatchesTheReference) {
  const std::vector<GpPrimitive> prims = readGpPrimitives(kGpDir / "plate_holes.fit");
  const std::vector<FitLine> fit = fitLines(kGpDir / "plate_holes.fit");
  const Aabb box = gpClipBox(prims);
  Rng rng(99);
  const std::function<std::string(int)> randomExpression = [&](int depth) -> std::string {
    const int pick = std::uniform_int_distribution<int>(0, depth > 0 ? 5 : 0)(rng);
    if (pick == 0) return prims[std::uniform_int_distribution<std::size_t>(0, 19)(rng)].name;
    if (pick == 1) return "negation[" + randomExpression(depth - 1) + "]";
    static const char* kOps[] = {"union", "intersection", "subtraction", "union"};
    return std::string(kOps[pick - 2]) + "[" + randomExpression(depth - 1) + "," +
           randomExpression(depth - 1) + "]";
  };
  for (int trial = 0; trial < 40; ++trial) {
    const std::string text = randomExpression(6);
    std::istringstream in(text);
    const CsgTree tree = readGpExpression(in, prims, box, "random");
    ReferenceExpression reference(text, fit);
    for (int i = 0; i < 300; ++i) {
      const Vec3 p = randomPoint(rng, box);
      EXPECT_NEAR(tree.value(p), reference.value(p), 1e-9 * box.diagonal()) << text;
    }
  }
}

// Spheres, cones and tori (not in the samples): parameter order and the
// leaves' values, the baseline's f where it is an exact distance.
TEST(GpFiles, SphereConeTorusLines) {
  std::istringstream fitText(
      "sphere 1 2 3 2\n"
      "torus 0 0 2 0 0 1 0.5 3\n"
      "cone 0 0 1 0 0 -1 0.5\n");
  const std::vector<GpPrimitive> prims = readGpPrimitives(fitText, "three.fit");
  ASSERT_EQ(prims.size(), 3u);
  EXPECT_EQ(prims[1].name, "torus1");
  const auto& torus = std::get<TorusSurface>(prims[1].shape);
  EXPECT_EQ(torus.minorRadius, 0.5);
  EXPECT_EQ(torus.majorRadius, 3.0);
  test::expectNear(torus.axisDir, Vec3::UnitZ(), 0.0);
  test::expectNear(torus.center, Vec3(0, 0, 1), 0.0);
  const auto& cone = std::get<ConeSurface>(prims[2].shape);
  test::expectNear(cone.apex, Vec3(0, 0, -1), 0.0);
  test::expectNear(cone.axisDir, Vec3::UnitZ(), 0.0);
  EXPECT_EQ(cone.halfAngle, 0.5);

  const Aabb box{Vec3::Constant(-5), Vec3::Constant(5)};
  std::istringstream exprText("union[sphere0,subtraction[torus1,cone2]]");
  const CsgTree tree = readGpExpression(exprText, prims, box, "three_expr.txt");
  const auto sphere = [](const Vec3& x) { return 2.0 - (x - Vec3(1, 2, 3)).norm(); };
  const auto torusF = [](const Vec3& x) {
    return 0.5 - std::hypot(std::hypot(x.x(), x.y()) - 3.0, x.z() - 1.0);
  };
  // In front of the apex (z > -1 and outside the apex's normal cone) the
  // baseline's cone value -(rho cos a - g sin a) is the exact distance.
  const auto coneF = [](const Vec3& x) {
    const double g = x.z() + 1.0, rho = std::hypot(x.x(), x.y());
    return -(std::cos(0.5) * rho - std::sin(0.5) * g);
  };
  Rng rng(8);
  int checked = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p = randomPoint(rng, box);
    if (p.z() + 1.0 < 2.0) continue;  // keep well in front of the apex
    const double expected = std::max(sphere(p), std::min(torusF(p), -coneF(p)));
    EXPECT_NEAR(tree.value(p), expected, 1e-12) << test::str(p);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(GpFiles, BlanksAnywhereBetweenTheParts) {
  const std::vector<GpPrimitive> prims = readGpPrimitives(kGpDir / "cube.fit");
  const Aabb box = gpClipBox(prims);
  std::istringstream a("union[plane0,negation[plane1]]");
  std::istringstream b(" \n union \t[ plane0 ,\r\n negation [ plane1 ] ] \n\n");
  EXPECT_TRUE(readGpExpression(a, prims, box).structurallyEqual(readGpExpression(b, prims, box)));
}

TEST(GpFiles, ClipBoxRules) {
  // One plane through the origin: all reference points coincide.
  const std::vector<GpPrimitive> one = {{"plane0", PlaneSurface{Vec3::UnitZ(), 0.0}}};
  const Aabb b = gpClipBox(one);
  test::expectNear(b.min, Vec3::Constant(-1), 0.0);
  test::expectNear(b.max, Vec3::Constant(1), 0.0);
  const std::vector<GpPrimitive> cube = readGpPrimitives(kGpDir / "cube.fit");
  const Aabb c = gpClipBox(cube);
  const double grow = 0.1 * 2.0 * std::sqrt(3.0);
  test::expectNear(c.min, Vec3::Constant(-1 - grow), 1e-12);
  test::expectNear(c.max, Vec3::Constant(1 + grow), 1e-12);
  const Aabb s = gpScanClipBox(Aabb{Vec3(0, 0, 0), Vec3(3, 4, 0)});
  test::expectNear(s.min, Vec3::Constant(-0.25), 1e-12);
  test::expectNear(s.max, Vec3(3.25, 4.25, 0.25), 1e-12);
  EXPECT_THROW(gpClipBox({}), std::invalid_argument);
  EXPECT_THROW(gpScanClipBox(Aabb{}), std::invalid_argument);
  EXPECT_THROW(gpScanClipBox(Aabb{Vec3::Ones(), Vec3::Ones()}), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Bad input: one line naming the file (and the line or position).

class GpBadInput : public test::TempDirTest {
 protected:
  // Expects reading `fitText` as a .fit file to fail with one line naming
  // it and containing `fragment`.
  void expectBadFit(const std::string& fitText, const std::string& fragment) {
    const fs::path p = write("bad.fit", fitText);
    try {
      readGpPrimitives(p);
      ADD_FAILURE() << "accepted: " << fitText;
    } catch (const ParseError& e) {
      expectOneLine(e.what(), p, fragment);
    }
  }
  // The same for an expression over the cube's six planes.
  void expectBadExpression(const std::string& exprText, const std::string& fragment) {
    const fs::path p = write("bad_expr.txt", exprText);
    const std::vector<GpPrimitive> prims = readGpPrimitives(kGpDir / "cube.fit");
    try {
      readGpExpression(p, prims, gpClipBox(prims));
      ADD_FAILURE() << "accepted: " << exprText.substr(0, 200);
    } catch (const ParseError& e) {
      expectOneLine(e.what(), p, fragment);
    }
  }
  static void expectOneLine(const std::string& message, const fs::path& p,
                            const std::string& fragment) {
    EXPECT_EQ(message.rfind(p.string() + ": ", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find(fragment), std::string::npos) << message;
    EXPECT_LT(message.size(), 400u) << message;
  }
};

TEST_F(GpBadInput, FitFiles) {
  expectBadFit("box 0 0 0 1\n", "line 1 (index 0): unknown primitive type 'box'");
  expectBadFit("plane 0 0 1 1\nplane 0 0 1\n", "line 2 (index 1): plane needs 4 numbers");
  expectBadFit("sphere 0 0 0 1 2\n", "sphere needs 4 numbers");
  expectBadFit("cylinder 0 0 1 0 0 0\n", "cylinder needs 7 numbers");
  expectBadFit("cone 0 0 1 0 0 0 0.5 1\n", "cone needs 7 numbers");
  expectBadFit("torus 0 0 1 0 0 0 1\n", "torus needs 8 numbers");
  expectBadFit("plane 0 0 1 nan\n", "'nan' is not a finite number");
  expectBadFit("plane 0 0 1 inf\n", "'inf' is not a finite number");
  expectBadFit("plane 0 0 1 1e999\n", "'1e999' is not a finite number");
  expectBadFit("plane 0 0 1 1x\n", "'1x' is not a finite number");
  expectBadFit("plane 0 0 0 1\n", "plane normal has zero length");
  expectBadFit("cylinder 0 0 0 0 0 0 1\n", "cylinder axis has zero length");
  expectBadFit("cylinder 0 0 1 0 0 0 -1\n", "cylinder radius must be > 0");
  expectBadFit("sphere 0 0 0 0\n", "sphere radius must be > 0");
  expectBadFit("cone 0 0 1 0 0 0 2\n", "cone half-angle");
  expectBadFit("cone 0 0 1 0 0 0 0\n", "cone half-angle");
  expectBadFit("torus 0 0 1 0 0 0 2 1\n", "spindle torus");
  expectBadFit("plane 0 0 1 1\n\nplane 0 0 1 2\n", "line 2 (index 1) is empty");
  expectBadFit("", "no primitives");
  expectBadFit(" \n\t\n", "no primitives");
  expectBadFit(std::string("\x7f\x45\x4c\x46\x02\x01\x00\x00 1 2", 12), "unknown primitive type");
  // Blank lines at the end are fine.
  EXPECT_EQ(readGpPrimitives(write("ok.fit", "plane 0 0 1 1\r\n\n \n")).size(), 1u);
}

TEST_F(GpBadInput, ExpressionFiles) {
  expectBadExpression("plane6", "line 1, column 1: 'plane6' indexes line 6");
  expectBadExpression("plane99999999999999999999999", "indexes line");
  expectBadExpression("union[plane0,sphere1]", "column 14: 'sphere1': primitive 1");
  expectBadExpression("union[plane0,plane1", "unexpected end");
  expectBadExpression("union[plane0,plane1]]", "unexpected text after the expression");
  expectBadExpression("union[plane0,plane1] plane2", "unexpected text after the expression");
  expectBadExpression("plane0]", "unexpected text after the expression");
  expectBadExpression("union[plane0 plane1]", "expected ',' or ']'");
  expectBadExpression("union[plane0,]", "expected an operation or a leaf");
  expectBadExpression("union plane0", "expected '[' after 'union'");
  expectBadExpression("xor[plane0,plane1]", "'xor' is neither an operation");
  expectBadExpression("plane", "'plane' is neither an operation");
  expectBadExpression("union[plane0]", "union takes 2 operands, got 1");
  expectBadExpression("negation[plane0,plane1]", "negation takes 1 operand");
  expectBadExpression("intersection[plane0,plane1,plane2]", "intersection takes 2 operands");
  expectBadExpression("", "empty expression");
  expectBadExpression(" \n ", "empty expression");
  expectBadExpression("union[plane0,\n  plane1)", "line 2, column 9: expected ',' or ']'");
  // Deep nesting is refused without recursion (no stack overflow).
  for (std::size_t depth : {std::size_t{901}, std::size_t{10'000}, std::size_t{1'000'000}}) {
    std::string deep;
    for (std::size_t i = 0; i < depth; ++i) deep += "negation[";
    deep += "plane0";
    deep += std::string(depth, ']');
    expectBadExpression(deep, "nested more than 900 levels");
  }
  expectBadExpression(std::string(1'000'000, '['), "expected an operation or a leaf");
}

TEST_F(GpBadInput, MissingFilesAreIoErrors) {
  EXPECT_THROW(readGpPrimitives(dir_ / "none.fit"), IoError);
  EXPECT_THROW(readGpPrimitives(dir_), IoError);
  const std::vector<GpPrimitive> prims = readGpPrimitives(kGpDir / "cube.fit");
  EXPECT_THROW(readGpExpression(dir_ / "none.txt", prims, gpClipBox(prims)), IoError);
  EXPECT_THROW(readGpExpression(kGpDir / "cube_expr.txt", prims, Aabb{}), std::invalid_argument);
}

// The deepest expression accepted still makes a tree that tree.json reads.
TEST_F(GpBadInput, DeepestAcceptedTreeRoundTripsThroughTreeJson) {
  std::string deep;
  for (std::size_t i = 0; i < kMaxGpNesting; ++i) deep += "negation[";
  deep += "plane0" + std::string(kMaxGpNesting, ']');
  const fs::path expr = write("deep.txt", deep);
  const GpImport imported = importGp(kGpDir / "cube.fit", expr);
  EXPECT_EQ(imported.tree.depth(), kMaxGpNesting + 2);
  std::stringstream json;
  writeTreeJson(json, imported.tree);
  const CsgTree back = readTreeJson(json, "deep.json");
  EXPECT_TRUE(back.structurallyEqual(imported.tree));
}

// ---------------------------------------------------------------------------
// The command

class ImportGpCli : public Cli {};

TEST_F(ImportGpCli, BothSamplesImportAndRenderAndEvaluate) {
  const std::string d = kGpDir.string();
  const RunResult help = run("import-gp --help", dir_);
  EXPECT_EQ(help.code, 0);
  for (const char* word : {"cylinder ax ay az px py pz r", "negation[A]", "--scan", "tree.scad"}) {
    EXPECT_NE(help.out.find(word), std::string::npos) << word;
  }
  for (const char* sample : {"cube", "plate_holes"}) {
    SCOPED_TRACE(sample);
    const std::string fit = d + "/" + sample + ".fit";
    const std::string expr = d + "/" + sample + "_expr.txt";
    const fs::path json = dir_ / (std::string(sample) + ".json");
    const RunResult r = run("import-gp " + fit + " " + expr + " -o " + json.string(), dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    const CsgTree tree = readTreeJson(json);
    EXPECT_EQ(tree.leaves().back()->name, "clip_box");
    // The same tree as the library's import.
    EXPECT_TRUE(tree.structurallyEqual(importGp(fit, expr).tree));

    const fs::path folder = dir_ / (std::string(sample) + "-out");
    ASSERT_EQ(run("import-gp " + fit + " " + expr + " -o " + folder.string() + " -q", dir_).code,
              0);
    for (const char* name : {"tree.json", "tree.scad", "tree.txt"}) {
      EXPECT_TRUE(fs::is_regular_file(folder / name)) << name;
    }
    EXPECT_NE(slurp(folder / "tree.txt").find("clip_box"), std::string::npos);

    const RunResult render = run(
        "render " + json.string() + " -o " + (dir_ / "mesh.ply").string() + " --res 32 -q", dir_);
    EXPECT_EQ(render.code, 0) << render.err;
    // A scan sampled from the imported solid itself: eval reads the tree and
    // finds it fits.
    const std::string scan = (dir_ / "scan.ply").string();
    ASSERT_EQ(run("sample " + json.string() + " -o " + scan + " --points 3000 -q", dir_).code, 0);
    const RunResult eval = run("eval " + json.string() + " " + scan + " --json -q", dir_);
    ASSERT_EQ(eval.code, 0) << eval.err;
    EXPECT_LT(nlohmann::json::parse(eval.out).at("max_distance_relative").get<double>(), 0.01);
  }
  // With a scan, its box (grown by 5 % of its diagonal) is the clip box.
  const std::string scan = (dir_ / "scan.ply").string();  // of plate_holes' imported slab
  const fs::path withScan = dir_ / "with_scan.json";
  const RunResult r = run("import-gp " + d + "/plate_holes.fit " + d + "/plate_holes_expr.txt -o " +
                              withScan.string() + " --scan " + scan,
                          dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("(from the scan)"), std::string::npos) << r.err;
}

TEST_F(ImportGpCli, BadFilesAreOneLineNamingThem) {
  const std::string d = kGpDir.string();
  const fs::path badFit = dir_ / "bad.fit";
  write(badFit, "plane 0 0 1 1\nplane 0 0 1\n");
  expectCleanError(
      "import-gp " + badFit.string() + " " + d + "/cube_expr.txt -o " + (dir_ / "t.json").string(),
      badFit.string());
  const fs::path badExpr = dir_ / "bad_expr.txt";
  write(badExpr, "union[plane0,plane9]");
  expectCleanError(
      "import-gp " + d + "/cube.fit " + badExpr.string() + " -o " + (dir_ / "out").string(),
      badExpr.string());
  EXPECT_FALSE(fs::exists(dir_ / "t.json"));
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  // The output may not replace an input.
  const fs::path fitCopy = dir_ / "cube.json";
  fs::copy_file(kGpDir / "cube.fit", fitCopy);
  expectCleanError(
      "import-gp " + fitCopy.string() + " " + d + "/cube_expr.txt -o " + fitCopy.string(),
      fitCopy.string());
  EXPECT_EQ(slurp(fitCopy), slurp(kGpDir / "cube.fit"));
}

}  // namespace
}  // namespace csgvox
