// Tests for io/tree_json.h: lossless round trips, hand-written documents and
// clear errors for malformed input.

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "io/errors.h"
#include "io/tree_json.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;
using test::Rng;

// Every parameter of a primitive, in a fixed order.
std::vector<double> parameters(const Primitive& p) {
  std::vector<double> out;
  auto add = [&](const Vec3& v) { out.insert(out.end(), v.data(), v.data() + 3); };
  if (const auto* s = p.as<HalfSpace>()) {
    add(s->normal);
    out.push_back(s->offset);
  } else if (const auto* s = p.as<Box>()) {
    add(s->center);
    for (int i = 0; i < 3; ++i) add(s->axes.col(i));
    add(s->halfSize);
  } else if (const auto* s = p.as<Cylinder>()) {
    add(s->center);
    add(s->axis);
    out.insert(out.end(), {s->radius, s->height});
  } else if (const auto* s = p.as<Cone>()) {
    add(s->center);
    add(s->axis);
    out.insert(out.end(), {s->radiusBottom, s->radiusTop, s->height});
  } else if (const auto* s = p.as<Sphere>()) {
    add(s->center);
    out.push_back(s->radius);
  } else if (const auto* s = p.as<Torus>()) {
    add(s->center);
    add(s->axis);
    out.insert(out.end(), {s->majorRadius, s->minorRadius});
  }
  return out;
}

// Same structure, leaf names, primitive types and bit patterns of every number.
void expectBitIdentical(const Node& a, const Node& b, const std::string& where = "root") {
  SCOPED_TRACE(where);
  ASSERT_EQ(a.kind, b.kind);
  ASSERT_EQ(a.children.size(), b.children.size());
  if (a.kind == NodeKind::Primitive) {
    EXPECT_EQ(a.name, b.name);
    ASSERT_EQ(a.primitive.type(), b.primitive.type());
    const std::vector<double> pa = parameters(a.primitive), pb = parameters(b.primitive);
    ASSERT_EQ(pa.size(), pb.size());
    for (std::size_t i = 0; i < pa.size(); ++i) {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(pa[i]), std::bit_cast<std::uint64_t>(pb[i]))
          << "parameter " << i << ": " << pa[i] << " vs " << pb[i];
    }
  }
  for (std::size_t i = 0; i < a.children.size(); ++i) {
    expectBitIdentical(*a.children[i], *b.children[i], where + "." + std::to_string(i));
  }
}

std::string toJson(const CsgTree& t) {
  std::ostringstream out;
  writeTreeJson(out, t);
  return out.str();
}

CsgTree fromJson(const std::string& text, const std::string& source = "doc.json") {
  std::istringstream in(text);
  return readTreeJson(in, source);
}

// A tree with every primitive type and every operation, with awkward numbers:
// random full-precision doubles, 0.1, 1/3, -0.0, a subnormal, huge and tiny.
CsgTree everythingTree(std::uint64_t seed) {
  Rng rng(seed);
  auto leaf = [&](PrimitiveType t, const std::string& name) {
    return CsgTree::leaf(test::randomPrimitive(t, rng), name);
  };
  Box box = *test::randomPrimitive(PrimitiveType::Box, rng).as<Box>();
  box.center = Vec3(0.1, 1.0 / 3.0, -0.0);
  const CsgTree half1 = CsgTree::leaf(HalfSpace{test::randomUnit(rng), 4.9e-324}, "denormal cut");
  const CsgTree half2 = CsgTree::leaf(HalfSpace{Vec3(0, 0, -1), 1e300}, "");
  const CsgTree sphere =
      CsgTree::leaf(Sphere{Vec3(1e-300, -2.5e-17, 123456789.123456789), 1e-9}, "tiny");
  const CsgTree body =
      CsgTree::subtract({CsgTree::leaf(box, "base"), leaf(PrimitiveType::Cylinder, "bore"),
                         leaf(PrimitiveType::Cone, "chamfer"), CsgTree::complement(half1)});
  return CsgTree::unite(
      {body, CsgTree::intersect({leaf(PrimitiveType::Sphere, "ball"), CsgTree::complement(half2)}),
       leaf(PrimitiveType::Torus, "ring \"quoted\" \\ ünïcode"), sphere,
       CsgTree::leaf(Cone{Vec3::Zero(), Vec3::UnitX(), 0.0, 2.0, 1.0}, "pointed")});
}

// ---------------------------------------------------------------------------
// Round trips.

TEST(TreeJson, RoundTripIsLossless) {
  const CsgTree t = everythingTree(1);
  ASSERT_NO_THROW(t.validate());
  const std::string text = toJson(t);
  const CsgTree back = fromJson(text);
  EXPECT_TRUE(back.structurallyEqual(t, 0.0));
  expectBitIdentical(*t.root(), *back.root());
  // Written again, the text is identical.
  EXPECT_EQ(toJson(back), text);
  // Every type and operation really is in the file.
  for (const char* word : {"\"halfspace\"", "\"box\"", "\"cylinder\"", "\"cone\"", "\"sphere\"",
                           "\"torus\"", "\"union\"", "\"intersection\"", "\"difference\"",
                           "\"complement\"", "\"format\": \"csgvox-tree\"", "\"version\": 1"}) {
    EXPECT_NE(text.find(word), std::string::npos) << word;
  }
}

TEST(TreeJson, RandomTreesRoundTrip) {
  Rng rng(2);
  for (int i = 0; i < 30; ++i) {
    const CsgTree t = test::randomTree(rng, 1 + i % 7);
    const CsgTree back = fromJson(toJson(t));
    EXPECT_TRUE(back.structurallyEqual(t, 0.0)) << "tree " << i;
    expectBitIdentical(*t.root(), *back.root());
  }
}

TEST(TreeJson, SingleLeafRoundTrip) {
  const CsgTree t = CsgTree::leaf(Sphere{Vec3(1, 2, 3), 4});  // no name
  const std::string text = toJson(t);
  EXPECT_EQ(text.find("\"name\""), std::string::npos);  // an empty name is not written
  const CsgTree back = fromJson(text);
  expectBitIdentical(*t.root(), *back.root());
  EXPECT_EQ(back.root()->name, "");
}

class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("csgvox_test_tree_json_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

using TreeJsonFile = TempDir;

TEST_F(TreeJsonFile, RoundTripThroughAFile) {
  const CsgTree t = everythingTree(3);
  const fs::path file = dir_ / "tree.json";
  writeTreeJson(file, t);
  ASSERT_TRUE(fs::exists(file));
  const CsgTree back = readTreeJson(file);
  EXPECT_TRUE(back.structurallyEqual(t, 0.0));
  expectBitIdentical(*t.root(), *back.root());
  // Only the file itself is left behind (no temporary).
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++entries;
  EXPECT_EQ(entries, 1);
}

TEST_F(TreeJsonFile, MissingFileIsAnIoError) {
  const fs::path file = dir_ / "nope.json";
  try {
    readTreeJson(file);
    ADD_FAILURE() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.json"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readTreeJson(dir_), IoError);  // a directory
}

TEST_F(TreeJsonFile, BadFileContentIsAParseErrorNamingTheFile) {
  const fs::path file = dir_ / "broken.json";
  std::ofstream(file) << "{\"root\": {\"type\": \"sphere\", \"center\": [0, 0, 0]}}";
  try {
    readTreeJson(file);
    ADD_FAILURE() << "no exception";
  } catch (const ParseError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(file.string() + ":", 0), 0u) << what;
    EXPECT_NE(what.find("radius"), std::string::npos) << what;
  }
}

TEST_F(TreeJsonFile, WriteErrors) {
  const CsgTree t = CsgTree::leaf(Sphere{});
  EXPECT_THROW(writeTreeJson(dir_ / "missing_dir" / "tree.json", t), IoError);
  EXPECT_THROW(writeTreeJson(dir_, t), IoError);
  std::ostringstream out;
  EXPECT_THROW(writeTreeJson(out, CsgTree()), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Hand-written documents.

TEST(TreeJson, ReadsTheReadmeExample) {
  const CsgTree t = fromJson(R"({
    "format": "csgvox-tree",
    "version": 1,
    "root": {
      "op": "difference",
      "children": [
        { "type": "box", "name": "plate", "center": [0, 0, 2.5],
          "axes": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "half_size": [40, 30, 2.5] },
        { "type": "cylinder", "name": "hole", "center": [30, 20, 2.5],
          "axis": [0, 0, 1], "radius": 4, "height": 7 }
      ]
    }
  })");
  const CsgTree expected =
      CsgTree::subtract({CsgTree::leaf(Box{Vec3(0, 0, 2.5), Mat3::Identity(), Vec3(40, 30, 2.5)}),
                         CsgTree::leaf(Cylinder{Vec3(30, 20, 2.5), Vec3::UnitZ(), 4.0, 7.0})});
  EXPECT_TRUE(t.structurallyEqual(expected, 0.0));
  ASSERT_EQ(t.leaves().size(), 2u);
  EXPECT_EQ(t.leaves()[0]->name, "plate");
  EXPECT_EQ(t.leaves()[1]->name, "hole");
  EXPECT_TRUE(t.contains(Vec3(0, 0, 2.5)));
  EXPECT_FALSE(t.contains(Vec3(30, 20, 2.5)));
}

TEST(TreeJson, ReadsEveryPrimitiveAndOperation) {
  const CsgTree t = fromJson(R"({"root": {"op": "union", "children": [
    {"op": "intersection", "children": [
      {"type": "sphere", "name": "ball", "center": [1, 2, 3], "radius": 2},
      {"op": "complement", "children": [{"type": "halfspace", "normal": [0, 0, 1], "offset": 2.5}]}
    ]},
    {"type": "torus", "center": [0, 0, -5], "axis": [0, 1, 0],
     "major_radius": 3, "minor_radius": 0.5},
    {"type": "cone", "center": [5, 0, 0], "axis": [1, 0, 0], "radius_bottom": 1, "radius_top": 0,
     "height": 2},
    {"type": "box", "center": [0, 5, 0], "half_size": [1, 2, 3],
     "axes": [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]}
  ]}})");
  Mat3 rot;
  rot.col(0) = Vec3(0, 1, 0);
  rot.col(1) = Vec3(-1, 0, 0);
  rot.col(2) = Vec3(0, 0, 1);
  const CsgTree expected = CsgTree::unite(
      {CsgTree::intersect({CsgTree::leaf(Sphere{Vec3(1, 2, 3), 2.0}),
                           CsgTree::complement(CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 2.5}))}),
       CsgTree::leaf(Torus{Vec3(0, 0, -5), Vec3::UnitY(), 3.0, 0.5}),
       CsgTree::leaf(Cone{Vec3(5, 0, 0), Vec3::UnitX(), 1.0, 0.0, 2.0}),
       CsgTree::leaf(Box{Vec3(0, 5, 0), rot, Vec3(1, 2, 3)})});
  EXPECT_TRUE(t.structurallyEqual(expected, 0.0));
  EXPECT_EQ(t.leaves()[0]->name, "ball");
  // "axes" lists the box's own axes: its first axis is world +y, so the
  // half size 1 is measured along y.
  EXPECT_TRUE(t.contains(Vec3(1.9, 5.9, 0)));
  EXPECT_FALSE(t.contains(Vec3(0, 6.5, 0)));
}

TEST(TreeJson, BoxAxesDefaultToTheWorldAxes) {
  const CsgTree t =
      fromJson(R"({"root": {"type": "box", "center": [0, 0, 0], "half_size": [1, 2, 3]}})");
  ASSERT_EQ(t.nodeCount(), 1u);
  const Box* b = t.root()->primitive.as<Box>();
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(b->axes, Mat3::Identity());
  EXPECT_EQ(b->halfSize, Vec3(1, 2, 3));
}

// ---------------------------------------------------------------------------
// Malformed input.

struct BadDoc {
  std::string label;
  std::string json;
  std::vector<std::string> expected;  // each must appear in the message
};

std::string wrapRoot(const std::string& node) {
  return R"({"format": "csgvox-tree", "version": 1, "root": )" + node + "}";
}

const std::string kSphere = R"({"type": "sphere", "center": [0, 0, 0], "radius": 1})";

std::vector<BadDoc> badDocuments() {
  return {
      {"NotJson", "this is not json", {"not valid JSON"}},
      {"Empty", "", {"not valid JSON"}},
      {"Truncated", R"({"root": {"type": "sphere", "center": [0, 0)", {"not valid JSON"}},
      {"TopLevelArray", "[1, 2, 3]", {"top level", "object"}},
      {"MissingRoot", R"({"format": "csgvox-tree", "version": 1})", {"missing \"root\""}},
      {"WrongFormat", R"({"format": "other", "root": )" + kSphere + "}", {"format"}},
      {"Version2",
       R"({"format": "csgvox-tree", "version": 2, "root": )" + kSphere + "}",
       {"version", "2"}},
      {"Version0", R"({"version": 0, "root": )" + kSphere + "}", {"version"}},
      {"VersionWraps", R"({"version": 4294967297, "root": )" + kSphere + "}", {"version"}},
      {"VersionString", R"({"version": "1", "root": )" + kSphere + "}", {"version"}},
      {"RootNotObject", R"({"root": 42})", {"root", "object"}},
      {"UnknownType", wrapRoot(R"({"type": "pyramid", "center": [0, 0, 0]})"), {"root", "pyramid"}},
      {"TypeNotString", wrapRoot(R"({"type": 3})"), {"\"type\""}},
      {"NeitherTypeNorOp", wrapRoot(R"({"center": [0, 0, 0]})"), {"\"type\"", "\"op\""}},
      {"UnknownOp", wrapRoot(R"({"op": "xor", "children": [)" + kSphere + "]}"), {"xor"}},
      {"OpWithoutChildren", wrapRoot(R"({"op": "union"})"), {"union", "children"}},
      {"OpWithEmptyChildren", wrapRoot(R"({"op": "intersection", "children": []})"), {"children"}},
      {"ChildrenNotArray", wrapRoot(R"({"op": "union", "children": {}})"), {"children"}},
      {"ComplementTwoChildren",
       wrapRoot(R"({"op": "complement", "children": [)" + kSphere + "," + kSphere + "]}"),
       {"complement", "one child"}},
      {"ChildNotObject",
       wrapRoot(R"({"op": "union", "children": [)" + kSphere + ", 7]}"),
       {"root.children[1]", "object"}},
      {"VectorTooShort",
       wrapRoot(R"({"type": "sphere", "center": [0, 0], "radius": 1})"),
       {"\"center\"", "3 numbers"}},
      {"VectorTooLong",
       wrapRoot(R"({"type": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1, 0],
                                     "radius": 1, "height": 1})"),
       {"\"axis\"", "3 numbers"}},
      {"VectorOfStrings",
       wrapRoot(R"({"type": "sphere", "center": ["0", "0", "0"], "radius": 1})"),
       {"\"center\""}},
      {"MissingVector", wrapRoot(R"({"type": "sphere", "radius": 1})"), {"center"}},
      {"RadiusNotNumber",
       wrapRoot(R"({"type": "sphere", "center": [0, 0, 0], "radius": "1.0"})"),
       {"\"radius\"", "number"}},
      {"RadiusNull",
       wrapRoot(R"({"type": "sphere", "center": [0, 0, 0], "radius": null})"),
       {"\"radius\""}},
      {"MissingRadius", wrapRoot(R"({"type": "sphere", "center": [0, 0, 0]})"), {"\"radius\""}},
      {"NegativeRadius",
       wrapRoot(R"({"op": "difference", "children": [)" + kSphere +
                R"(, {"type": "cylinder", "name": "hole", "center": [0, 0, 0],
                                        "axis": [0, 0, 1], "radius": -1, "height": 2}]})"),
       {"root.children[1]", "hole", "radius"}},
      {"ZeroHeight",
       wrapRoot(R"({"type": "cone", "center": [0, 0, 0], "axis": [0, 0, 1],
                                  "radius_bottom": 1, "radius_top": 0, "height": 0})"),
       {"height"}},
      {"NonUnitAxis",
       wrapRoot(R"({"type": "torus", "center": [0, 0, 0], "axis": [0, 0, 2],
                                   "major_radius": 2, "minor_radius": 1})"),
       {"axis", "unit"}},
      {"NonUnitNormal",
       wrapRoot(R"({"type": "halfspace", "normal": [1, 1, 0], "offset": 0})"),
       {"normal"}},
      {"MinorAboveMajor",
       wrapRoot(R"({"type": "torus", "center": [0, 0, 0], "axis": [0, 0, 1],
                                       "major_radius": 1, "minor_radius": 2})"),
       {"minor radius"}},
      {"AxesNotOrthonormal",
       wrapRoot(R"({"type": "box", "center": [0, 0, 0], "half_size": [1, 1, 1],
                                          "axes": [[1, 0, 0], [1, 0, 0], [0, 0, 1]]})"),
       {"axes"}},
      {"AxesWrongCount",
       wrapRoot(R"({"type": "box", "center": [0, 0, 0], "half_size": [1, 1, 1],
                                      "axes": [[1, 0, 0], [0, 1, 0]]})"),
       {"\"axes\""}},
      {"AxesEntryTooShort",
       wrapRoot(R"({"type": "box", "center": [0, 0, 0], "half_size": [1, 1, 1],
                                         "axes": [[1, 0, 0], [0, 1], [0, 0, 1]]})"),
       {"\"axes\"[1]", "3 numbers"}},
      {"NameNotString",
       wrapRoot(R"({"type": "sphere", "name": 5, "center": [0, 0, 0], "radius": 1})"),
       {"\"name\""}},
      {"NumberOverflow",
       wrapRoot(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e400})"),
       {"doc.json"}},
  };
}

class TreeJsonMalformed : public ::testing::TestWithParam<BadDoc> {};

void PrintTo(const BadDoc& d, std::ostream* os) { *os << d.label; }

TEST_P(TreeJsonMalformed, ThrowsParseErrorWithAHelpfulMessage) {
  const BadDoc& d = GetParam();
  try {
    fromJson(d.json, "doc.json");
    ADD_FAILURE() << "accepted: " << d.json;
  } catch (const ParseError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("doc.json: ", 0), 0u)
        << "message does not start with the source: " << what;
    for (const std::string& s : d.expected) {
      EXPECT_NE(what.find(s), std::string::npos) << "'" << s << "' not in: " << what;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a ParseError: " << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Documents, TreeJsonMalformed, ::testing::ValuesIn(badDocuments()),
                         [](const ::testing::TestParamInfo<BadDoc>& info) {
                           return info.param.label;
                         });

// `levels` nested unions around one sphere.
std::string nestedDocument(int levels) {
  std::string doc = R"({"root": )";
  for (int i = 0; i < levels; ++i) doc += R"({"op": "union", "children": [)";
  doc += kSphere;
  for (int i = 0; i < levels; ++i) doc += "]}";
  return doc + "}";
}

TEST(TreeJson, DeepNesting) {
  // 1000 levels of operations are read (and evaluated) fine.
  const CsgTree deep = fromJson(nestedDocument(1000));
  EXPECT_EQ(deep.depth(), 1001u);
  EXPECT_DOUBLE_EQ(deep.value(Vec3(0.5, 0, 0)), 0.5);
  // Deeper is rejected cleanly, with a short message.
  try {
    fromJson(nestedDocument(1001));
    ADD_FAILURE() << "no exception";
  } catch (const ParseError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nested too deeply"), std::string::npos) << what.substr(0, 300);
    EXPECT_LT(what.size(), 400u) << "the location should be abbreviated";
  }
  EXPECT_THROW(fromJson(nestedDocument(20000)), ParseError);
}

// Locations of moderately deep nodes are written out in full.
TEST(TreeJson, ErrorsNameTheNode) {
  std::string doc = R"({"root": )";
  for (int i = 0; i < 3; ++i) doc += R"({"op": "union", "children": [)" + kSphere + ",";
  doc += R"({"type": "sphere", "name": "bad", "center": [0, 0, 0], "radius": 0})";
  for (int i = 0; i < 3; ++i) doc += "]}";
  doc += "}";
  try {
    fromJson(doc);
    ADD_FAILURE() << "no exception";
  } catch (const ParseError& e) {
    const std::string expected = R"(root.children[1].children[1].children[1] "bad": sphere radius)";
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace csgvox
