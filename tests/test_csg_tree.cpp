// Tests for primitives/csg_tree.h: counts, evaluation against an independent
// classification, bounds, structural equality, validation and the sharing of
// immutable subtrees.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "core/csg_tree.h"
#include "core/tree_program.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::Rng;

static_assert(std::is_const_v<NodePtr::element_type>, "tree nodes must be immutable");

// A 10 x 6 x 1 plate with a boss on top and three through holes:
// difference(union(plate, boss), hole1, hole2, hole3).
struct Hole {
  double x, y, r;
};
const std::vector<Hole> kHoles = {{-3, 0, 0.6}, {0, 1, 0.4}, {3, -1, 0.8}};

CsgTree plateWithHoles(const std::string& prefix = "") {
  const CsgTree plate =
      CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(5, 3, 0.5)}, prefix + "plate");
  const CsgTree boss =
      CsgTree::leaf(Cylinder{Vec3(0, -2, 1), Vec3::UnitZ(), 0.5, 1.0}, prefix + "boss");
  std::vector<CsgTree> operands = {CsgTree::unite({plate, boss})};
  for (std::size_t i = 0; i < kHoles.size(); ++i) {
    const Hole& h = kHoles[i];
    operands.push_back(CsgTree::leaf(Cylinder{Vec3(h.x, h.y, 0), Vec3::UnitZ(), h.r, 2.0},
                                     prefix + "hole" + std::to_string(i + 1)));
  }
  return CsgTree::subtract(operands);
}

// Classification of the plate written from its description, not from fields.
bool insidePlate(const Vec3& p) {
  const bool plate = std::abs(p.x()) <= 5 && std::abs(p.y()) <= 3 && std::abs(p.z()) <= 0.5;
  const bool boss = std::hypot(p.x(), p.y() + 2) <= 0.5 && p.z() >= 0.5 && p.z() <= 1.5;
  if (!plate && !boss) return false;
  for (const Hole& h : kHoles) {
    if (std::hypot(p.x() - h.x, p.y() - h.y) <= h.r && std::abs(p.z()) <= 1.0) return false;
  }
  return true;
}

const Aabb kPlateBox{Vec3(-6, -4, -1), Vec3(6, 4, 2)};

CsgTree sphere(const Vec3& c, double r, const std::string& name = "") {
  return CsgTree::leaf(Sphere{c, r}, name);
}

std::vector<std::string> leafNames(const CsgTree& t) {
  std::vector<std::string> names;
  for (const Node* n : t.leaves()) names.push_back(n->name);
  return names;
}

// ---------------------------------------------------------------------------
// Counts and structure.

TEST(CsgTree, EmptyTree) {
  const CsgTree t;
  EXPECT_TRUE(t.empty());
  EXPECT_EQ(t.nodeCount(), 0u);
  EXPECT_EQ(t.operationCount(), 0u);
  EXPECT_EQ(t.primitiveCount(), 0u);
  EXPECT_EQ(t.depth(), 0u);
  EXPECT_TRUE(t.leaves().empty());
  EXPECT_EQ(t.value(Vec3::Zero()), -std::numeric_limits<double>::infinity());
  EXPECT_FALSE(t.contains(Vec3::Zero()));
  EXPECT_TRUE(t.bounds().isEmpty());
}

TEST(CsgTree, Leaf) {
  const CsgTree t = sphere(Vec3(1, 2, 3), 2.0, "ball");
  EXPECT_FALSE(t.empty());
  EXPECT_EQ(t.nodeCount(), 1u);
  EXPECT_EQ(t.operationCount(), 0u);
  EXPECT_EQ(t.primitiveCount(), 1u);
  EXPECT_EQ(t.depth(), 1u);
  ASSERT_EQ(t.leaves().size(), 1u);
  EXPECT_EQ(t.leaves()[0], t.root().get());
  EXPECT_EQ(t.root()->kind, NodeKind::Primitive);
  EXPECT_EQ(t.root()->name, "ball");
  EXPECT_DOUBLE_EQ(t.value(Vec3(1, 2, 3)), 2.0);
}

TEST(CsgTree, CountsDepthAndLeafOrder) {
  const CsgTree t = plateWithHoles();
  EXPECT_EQ(t.nodeCount(), 7u);
  EXPECT_EQ(t.operationCount(), 2u);
  EXPECT_EQ(t.primitiveCount(), 5u);
  EXPECT_EQ(t.depth(), 3u);
  EXPECT_EQ(leafNames(t), (std::vector<std::string>{"plate", "boss", "hole1", "hole2", "hole3"}));
  EXPECT_EQ(t.root()->kind, NodeKind::Difference);
  ASSERT_EQ(t.root()->children.size(), 4u);
  EXPECT_EQ(t.root()->children[0]->kind, NodeKind::Union);

  const CsgTree c = CsgTree::complement(CsgTree::complement(sphere(Vec3::Zero(), 1)));
  EXPECT_EQ(c.nodeCount(), 3u);
  EXPECT_EQ(c.operationCount(), 2u);
  EXPECT_EQ(c.depth(), 3u);

  // A subtree used twice counts twice.
  const CsgTree a = sphere(Vec3::Zero(), 1, "a");
  const CsgTree twice = CsgTree::unite({a, CsgTree::intersect({a, t})});
  EXPECT_EQ(twice.primitiveCount(), 7u);
  EXPECT_EQ(twice.nodeCount(), 11u);
  EXPECT_EQ(twice.depth(), 5u);
  EXPECT_EQ(leafNames(twice),
            (std::vector<std::string>{"a", "a", "plate", "boss", "hole1", "hole2", "hole3"}));
}

TEST(CsgTree, NodeKindNames) {
  EXPECT_EQ(nodeKindName(NodeKind::Primitive), "primitive");
  EXPECT_EQ(nodeKindName(NodeKind::Union), "union");
  EXPECT_EQ(nodeKindName(NodeKind::Intersection), "intersection");
  EXPECT_EQ(nodeKindName(NodeKind::Difference), "difference");
  EXPECT_EQ(nodeKindName(NodeKind::Complement), "complement");
}

TEST(CsgTree, OperationsNeedOperands) {
  EXPECT_THROW(CsgTree::unite({}), std::invalid_argument);
  EXPECT_THROW(CsgTree::intersect({}), std::invalid_argument);
  EXPECT_THROW(CsgTree::subtract({}), std::invalid_argument);
  EXPECT_THROW(CsgTree::unite({sphere(Vec3::Zero(), 1), CsgTree()}), std::invalid_argument);
  EXPECT_THROW(CsgTree::complement(CsgTree()), std::invalid_argument);
  // A single operand is allowed.
  const CsgTree one = CsgTree::unite({sphere(Vec3::Zero(), 1)});
  EXPECT_EQ(one.nodeCount(), 2u);
  EXPECT_DOUBLE_EQ(one.value(Vec3(0.25, 0, 0)), 0.75);
}

// ---------------------------------------------------------------------------
// Evaluation.

TEST(CsgTree, PlateWithHolesMatchesIndependentClassification) {
  const CsgTree t = plateWithHoles();
  Rng rng(1);
  int inside = 0, outside = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p = test::randomPoint(rng, kPlateBox);
    const double f = t.value(p);
    if (std::abs(f) < 1e-9) continue;
    const bool in = insidePlate(p);
    (in ? inside : outside)++;
    EXPECT_EQ(t.contains(p), in) << "at " << test::str(p) << " f = " << f;
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 1000);
  // Points in every hole, in the boss and in the solid plate.
  for (const Hole& h : kHoles) EXPECT_FALSE(t.contains(Vec3(h.x, h.y, 0)));
  EXPECT_TRUE(t.contains(Vec3(0, -2, 1.2)));
  EXPECT_FALSE(t.contains(Vec3(0, -2, 1.6)));
  EXPECT_TRUE(t.contains(Vec3(4.5, 2.5, 0.4)));
}

TEST(CsgTree, PlateWithHolesValues) {
  const CsgTree t = plateWithHoles();
  constexpr double kTol = 1e-12;
  EXPECT_NEAR(t.value(Vec3(-3, 0, 0)), -0.6, kTol);   // axis of hole 1: 0.6 to its wall
  EXPECT_NEAR(t.value(Vec3(-3, 0.9, 0)), 0.3, kTol);  // the hole wall is nearer than the faces
  EXPECT_NEAR(t.value(Vec3(4.8, 0, 0)), 0.2, kTol);   // near the +x face
  EXPECT_NEAR(t.value(Vec3(0, -2, 1.4)), 0.1, kTol);  // in the boss, near its top
  EXPECT_NEAR(t.value(Vec3(4, 2, 3)), -2.5, kTol);    // above the plate
  FieldValue v = t.evaluate(Vec3(-3, 0.9, 0));
  test::expectNear(v.gradient, Vec3(0, 1, 0), 1e-15);  // away from the hole wall
  v = t.evaluate(Vec3(4.8, 0, 0));
  test::expectNear(v.gradient, Vec3(-1, 0, 0), 1e-15);
}

TEST(CsgTree, GradientMatchesFiniteDifferences) {
  const CsgTree t = plateWithHoles();
  Rng rng(2);
  const auto fn = [&](const Vec3& p) { return t.value(p); };
  int checked = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 p = test::randomPoint(rng, kPlateBox);
    if (!test::isSmoothAt(fn, p, 1e-3)) continue;
    ++checked;
    EXPECT_TRUE(test::vecNear(t.evaluate(p).gradient, test::numericGradient(fn, p, 1e-6), 1e-6))
        << "at " << test::str(p);
    EXPECT_EQ(t.evaluate(p).f, t.value(p));
  }
  EXPECT_GT(checked, 270);
}

TEST(CsgTree, DifferenceWithSeveralSubtrahends) {
  const CsgTree a = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2, 1, 1)}, "a");
  const CsgTree b = sphere(Vec3(-2, 0, 0), 1.0, "b");
  const CsgTree c = sphere(Vec3(2, 0, 0), 1.2, "c");
  const CsgTree d = CsgTree::leaf(Cylinder{Vec3::Zero(), Vec3::UnitY(), 0.3, 5}, "d");
  const CsgTree multi = CsgTree::subtract({a, b, c, d});
  const CsgTree chained = CsgTree::subtract({CsgTree::subtract({CsgTree::subtract({a, b}), c}), d});
  const CsgTree viaComplement = CsgTree::intersect(
      {a, CsgTree::complement(b), CsgTree::complement(c), CsgTree::complement(d)});
  const CsgTree viaUnion = CsgTree::subtract({a, CsgTree::unite({b, c, d})});
  test::expectTreesEquivalent(multi, chained);
  test::expectTreesEquivalent(multi, viaComplement);
  test::expectTreesEquivalent(multi, viaUnion);
  // Every subtrahend is removed, not only the first one.
  EXPECT_TRUE(multi.contains(Vec3(-0.5, 0, 0.5)));
  EXPECT_FALSE(multi.contains(Vec3(-1.5, 0, 0)));
  EXPECT_FALSE(multi.contains(Vec3(1.5, 0, 0)));
  EXPECT_FALSE(multi.contains(Vec3(0, 0.5, 0)));
  Rng rng(3);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p = test::randomPoint(rng, Aabb{Vec3::Constant(-3), Vec3::Constant(3)});
    EXPECT_EQ(multi.value(p), viaComplement.value(p));
  }
}

TEST(CsgTree, Complement) {
  const CsgTree t = plateWithHoles();
  const CsgTree c = CsgTree::complement(t);
  const CsgTree cc = CsgTree::complement(c);
  Rng rng(4);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 p = test::randomPoint(rng, kPlateBox);
    const FieldValue v = t.evaluate(p), vc = c.evaluate(p);
    EXPECT_EQ(vc.f, -v.f);
    test::expectNear(vc.gradient, -v.gradient, 0.0);
    EXPECT_EQ(cc.value(p), v.f);
    if (v.f != 0.0) {
      EXPECT_NE(c.contains(p), t.contains(p));
    }
  }
  EXPECT_FALSE(c.bounds().isBounded());
  EXPECT_TRUE(c.contains(Vec3(100, 100, 100)));
}

TEST(CsgTree, AlgebraicIdentities) {
  Rng rng(5);
  for (int i = 0; i < 5; ++i) {
    const CsgTree a = CsgTree::leaf(test::randomBoundedPrimitive(rng));
    const CsgTree b = CsgTree::leaf(test::randomBoundedPrimitive(rng));
    const CsgTree c = CsgTree::leaf(test::randomBoundedPrimitive(rng));
    test::expectTreesEquivalent(CsgTree::unite({a, b}), CsgTree::unite({b, a}), 2000, 10 + i);
    test::expectTreesEquivalent(CsgTree::intersect({CsgTree::intersect({a, b}), c}),
                                CsgTree::intersect({a, CsgTree::intersect({b, c})}), 2000, 20 + i);
    // De Morgan, on unbounded trees (sampled in the fallback box).
    test::expectTreesEquivalent(
        CsgTree::complement(CsgTree::unite({a, b})),
        CsgTree::intersect({CsgTree::complement(a), CsgTree::complement(b)}), 2000, 30 + i);
  }
}

// The equivalence helper itself must notice different solids.
TEST(CsgTree, EquivalenceHelperDetectsDifferences) {
  const CsgTree a = sphere(Vec3::Zero(), 1.0);
  EXPECT_TRUE(test::treesEquivalent(a, sphere(Vec3::Zero(), 1.0), 2000, 1));
  EXPECT_FALSE(test::treesEquivalent(a, sphere(Vec3::Zero(), 1.1), 2000, 1));
  EXPECT_FALSE(test::treesEquivalent(a, sphere(Vec3(0.1, 0, 0), 1.0), 2000, 1));
  const CsgTree b = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3::Constant(0.5)});
  EXPECT_FALSE(
      test::treesEquivalent(CsgTree::subtract({a, b}), CsgTree::subtract({b, a}), 2000, 1));
  EXPECT_FALSE(test::treesEquivalent(CsgTree::unite({a, b}), CsgTree::intersect({a, b}), 2000, 1));
}

// ---------------------------------------------------------------------------
// Bounds.

TEST(CsgTree, BoundsOfOperations) {
  const CsgTree s = sphere(Vec3::Zero(), 1.0);
  const CsgTree small = sphere(Vec3(3, 0, 0), 0.5);
  const CsgTree slab = CsgTree::leaf(Box{Vec3(1, 0, 0), Mat3::Identity(), Vec3(0.5, 2, 2)});
  const CsgTree half = CsgTree::leaf(HalfSpace{Vec3::UnitX(), 0.0});

  Aabb b = CsgTree::unite({s, small}).bounds();
  test::expectNear(b.min, Vec3(-1, -1, -1), 1e-15);
  test::expectNear(b.max, Vec3(3.5, 1, 1), 1e-15);

  b = CsgTree::intersect({s, slab}).bounds();
  test::expectNear(b.min, Vec3(0.5, -1, -1), 1e-15);
  test::expectNear(b.max, Vec3(1, 1, 1), 1e-15);

  EXPECT_TRUE(CsgTree::intersect({s, small}).bounds().isEmpty());

  b = CsgTree::subtract({s, slab, small}).bounds();
  test::expectNear(b.min, Vec3(-1, -1, -1), 1e-15);
  test::expectNear(b.max, Vec3(1, 1, 1), 1e-15);

  EXPECT_FALSE(CsgTree::unite({s, half}).bounds().isBounded());
  // The half-space x <= 0 and the slab 0.5 <= x <= 1.5 have nothing in common.
  EXPECT_TRUE(CsgTree::intersect({half, slab}).bounds().isEmpty());
  const CsgTree cut = CsgTree::leaf(HalfSpace{Vec3::UnitX(), 1.0});
  b = CsgTree::intersect({cut, slab}).bounds();
  ASSERT_TRUE(b.isBounded());
  // Conservative (widened by a rounding slack of 1e-9 of the scale) and tight.
  EXPECT_TRUE((b.min.array() <= Vec3(0.5, -2, -2).array()).all()) << test::str(b.min);
  EXPECT_TRUE((b.max.array() >= Vec3(1.0, 2, 2).array()).all()) << test::str(b.max);
  test::expectNear(b.min, Vec3(0.5, -2, -2), 1e-8);
  test::expectNear(b.max, Vec3(1.0, 2, 2), 1e-8);
  EXPECT_FALSE(CsgTree::subtract({CsgTree::complement(s), slab}).bounds().isBounded());
  EXPECT_FALSE(CsgTree::complement(s).bounds().isBounded());

  b = plateWithHoles().bounds();
  test::expectNear(b.min, Vec3(-5, -3, -0.5), 1e-15);
  test::expectNear(b.max, Vec3(5, 3, 1.5), 1e-15);
}

// Bounds are conservative: every inside point of random trees lies in them.
TEST(CsgTree, BoundsContainTheSolid) {
  Rng rng(6);
  int insideTotal = 0;
  for (int t = 0; t < 30; ++t) {
    const CsgTree tree = test::randomTree(rng, 2 + t % 4);
    const Aabb b = tree.bounds();
    Aabb sampleBox;
    for (const Node* leaf : tree.leaves()) sampleBox.extend(leaf->primitive.bounds());
    sampleBox = sampleBox.grown(0.5);
    for (int i = 0; i < 500; ++i) {
      const Vec3 p = test::randomPoint(rng, sampleBox);
      if (!tree.contains(p)) continue;
      ++insideTotal;
      EXPECT_TRUE(b.contains(p)) << "tree " << t << " at " << test::str(p);
    }
  }
  EXPECT_GT(insideTotal, 300);
}

// ---------------------------------------------------------------------------
// Structural equality.

TEST(CsgTree, StructuralEquality) {
  const CsgTree t = plateWithHoles();
  EXPECT_TRUE(t.structurallyEqual(t));
  EXPECT_TRUE(t.structurallyEqual(plateWithHoles()));
  EXPECT_TRUE(t == plateWithHoles("renamed_"));  // names are ignored
  EXPECT_TRUE(CsgTree().structurallyEqual(CsgTree()));
  EXPECT_FALSE(CsgTree().structurallyEqual(t));
  EXPECT_FALSE(t.structurallyEqual(CsgTree()));

  const CsgTree a = sphere(Vec3::Zero(), 1.0), b = sphere(Vec3(1, 0, 0), 1.0);
  const CsgTree a2 = sphere(Vec3(0, 0, 1e-7), 1.0);
  EXPECT_FALSE(a.structurallyEqual(a2));
  EXPECT_FALSE(a == a2);
  EXPECT_TRUE(a.structurallyEqual(a2, 1e-6));
  EXPECT_FALSE(a.structurallyEqual(a2, 1e-8));
  EXPECT_TRUE(CsgTree::unite({a, b}).structurallyEqual(CsgTree::unite({a2, b}), 1e-6));
  EXPECT_FALSE(CsgTree::unite({a, b}).structurallyEqual(CsgTree::unite({a2, b}), 0.0));

  // Different structure.
  EXPECT_FALSE(CsgTree::unite({a, b}) == CsgTree::intersect({a, b}));
  EXPECT_FALSE(CsgTree::intersect({a, b}) == CsgTree::subtract({a, b}));
  EXPECT_FALSE(CsgTree::unite({a, b}) == CsgTree::unite({b, a}));
  EXPECT_FALSE(CsgTree::unite({a, b}) == CsgTree::unite({a, b, b}));
  EXPECT_FALSE(CsgTree::unite({a}) == a);
  EXPECT_FALSE(CsgTree::complement(a) == a);
  EXPECT_FALSE(CsgTree::complement(a) == CsgTree::unite({a}));
  EXPECT_FALSE(CsgTree::unite({a, CsgTree::unite({b, b})}) ==
               CsgTree::unite({CsgTree::unite({a, b}), b}));
  // Same solid, different primitive type.
  const CsgTree cyl = CsgTree::leaf(Cylinder{Vec3::Zero(), Vec3::UnitZ(), 1, 1});
  const CsgTree cone = CsgTree::leaf(Cone{Vec3::Zero(), Vec3::UnitZ(), 1, 1, 1});
  EXPECT_FALSE(cyl.structurallyEqual(cone, 1.0));
}

// ---------------------------------------------------------------------------
// Validation.

NodePtr makeNode(NodeKind kind, std::vector<NodePtr> children) {
  auto n = std::make_shared<Node>();
  n->kind = kind;
  n->children = std::move(children);
  return n;
}

void expectInvalid(const CsgTree& t, const std::string& expected) {
  try {
    t.validate();
    ADD_FAILURE() << "validate() accepted a tree with: " << expected;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos)
        << "message '" << e.what() << "' does not mention '" << expected << "'";
  }
}

TEST(CsgTree, ValidateAcceptsGoodTrees) {
  EXPECT_NO_THROW(plateWithHoles().validate());
  EXPECT_NO_THROW(CsgTree::complement(plateWithHoles()).validate());
  Rng rng(7);
  for (int i = 0; i < 10; ++i) EXPECT_NO_THROW(test::randomTree(rng, 5).validate());
}

TEST(CsgTree, ValidateReportsProblems) {
  expectInvalid(CsgTree(), "empty");
  const CsgTree bad = sphere(Vec3::Zero(), -1.0);
  expectInvalid(bad, "radius");
  expectInvalid(CsgTree::unite({plateWithHoles(), CsgTree::subtract({plateWithHoles(), bad})}),
                "radius");
  expectInvalid(CsgTree::leaf(Torus{Vec3::Zero(), Vec3::UnitZ(), 1.0, 2.0}), "minor radius");

  const NodePtr leaf = sphere(Vec3::Zero(), 1.0).root();
  expectInvalid(CsgTree(makeNode(NodeKind::Complement, {leaf, leaf})), "complement");
  expectInvalid(CsgTree(makeNode(NodeKind::Complement, {})), "complement");
  expectInvalid(CsgTree(makeNode(NodeKind::Union, {})), "union");
  expectInvalid(CsgTree(makeNode(NodeKind::Intersection, {})), "intersection");
  expectInvalid(CsgTree(makeNode(NodeKind::Difference, {})), "difference");
  expectInvalid(CsgTree(makeNode(NodeKind::Union, {leaf, nullptr})), "null");
  expectInvalid(CsgTree(makeNode(NodeKind::Primitive, {leaf})), "children");
  // Deep inside a valid-looking tree.
  const CsgTree wrapped = CsgTree::unite(
      {CsgTree(makeNode(NodeKind::Complement, {leaf, leaf})), sphere(Vec3::Zero(), 1)});
  expectInvalid(wrapped, "complement");
}

// ---------------------------------------------------------------------------
// Immutability and sharing.

TEST(CsgTree, EditsShareSubtreesAndLeaveTheOldTreeUnchanged) {
  const CsgTree a = sphere(Vec3::Zero(), 1.0, "a");
  const CsgTree b = sphere(Vec3(1, 0, 0), 0.5, "b");
  const CsgTree old = CsgTree::unite({a, b});
  const CsgTree snapshot = CsgTree::unite({sphere(Vec3::Zero(), 1.0), sphere(Vec3(1, 0, 0), 0.5)});
  const NodePtr oldRoot = old.root();
  const std::vector<NodePtr> oldChildren = old.root()->children;

  const CsgTree c = sphere(Vec3(0.5, 0, 0), 0.4, "c");
  const CsgTree edited = CsgTree::subtract({old, c});
  const CsgTree replaced =
      CsgTree::unite({CsgTree(old.root()->children[0]), c});  // "replace b by c"
  const CsgTree wrapped = CsgTree::complement(old);

  // The new trees point at the old nodes instead of copying them.
  EXPECT_EQ(edited.root()->children[0], old.root());
  EXPECT_EQ(wrapped.root()->children[0], old.root());
  EXPECT_EQ(replaced.root()->children[0], a.root());
  EXPECT_EQ(edited.leaves()[0], a.root().get());
  EXPECT_EQ(edited.leaves()[1], b.root().get());

  // The old tree is untouched.
  EXPECT_EQ(old.root(), oldRoot);
  EXPECT_EQ(old.root()->children, oldChildren);
  EXPECT_EQ(old.nodeCount(), 3u);
  EXPECT_EQ(old.root()->kind, NodeKind::Union);
  EXPECT_TRUE(old == snapshot);
  Rng rng(8);
  for (int i = 0; i < 200; ++i) {
    const Vec3 p = test::randomPoint(rng, Aabb{Vec3::Constant(-2), Vec3::Constant(2)});
    EXPECT_EQ(old.value(p), snapshot.value(p));
  }
  EXPECT_TRUE(old.contains(Vec3(0.5, 0, 0)));
  EXPECT_FALSE(edited.contains(Vec3(0.5, 0, 0)));

  // Copies of a tree are the same value (shared root), not deep copies.
  const CsgTree copy = edited;
  EXPECT_EQ(copy.root(), edited.root());
  EXPECT_TRUE(copy == edited);
}

// ---------------------------------------------------------------------------
// Value-only and batched evaluation.

// Points in the tree's bounds grown by a quarter on each side, plus points on
// and near the surface (the edge-crossing and sharpening paths of the mesher).
std::vector<Vec3> probePoints(const CsgTree& tree, Rng& rng, int count) {
  const Aabb b = tree.bounds();
  const Aabb box = b.grown(0.25 * b.size().maxCoeff());
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) points.push_back(test::randomPoint(rng, box));
  return points;
}

TEST(TreeEvaluation, ValueIsBitForBitTheEvaluatedValueOnTheBundledTrees) {
  Rng rng(21);
  for (const std::string& part : test::partNames()) {
    const CsgTree tree = readTreeJson(test::dataDir() / part / "tree.json");
    const std::vector<Vec3> points = probePoints(tree, rng, 20000);
    const SardfOperations sardf(sardfRadius(tree.bounds().diagonal()));
    for (const SetOperations* opsPtr :
         {&minMaxOperations(), &rFunctionOperations(), static_cast<const SetOperations*>(&sardf)}) {
      const SetOperations& ops = *opsPtr;
      std::vector<double> batched(points.size()), batchedByObject(points.size());
      if (ops.kind() != SetOperationKind::Sardf) tree.values(points, batched, ops.kind());
      tree.values(points, batchedByObject, ops);
      if (ops.kind() == SetOperationKind::Sardf) batched = batchedByObject;
      const TreeProgram program(tree);
      std::size_t mismatches = 0;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const double reference = tree.evaluate(points[i], ops).f;  // the gradient path
        mismatches += tree.value(points[i], ops) != reference;
        mismatches += batched[i] != reference;
        mismatches += batchedByObject[i] != reference;
        if (ops.kind() == SetOperationKind::MinMax) {
          mismatches += program.value(points[i]) != reference;
          const FieldValue v = program.evaluate(points[i]);
          const FieldValue w = tree.evaluate(points[i]);
          mismatches += v.f != w.f || v.gradient != w.gradient;
        }
      }
      EXPECT_EQ(mismatches, 0u) << part << " with " << ops.name();
    }
  }
}

TEST(TreeEvaluation, BatchedValuesMatchOnRandomTreesAndOddSizes) {
  Rng rng(22);
  for (int t = 0; t < 30; ++t) {
    const CsgTree tree = test::randomTree(rng, 1 + t % 9);
    // Sizes around the internal chunk length, and an empty batch.
    for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{255}, std::size_t{256},
                                std::size_t{257}, std::size_t{1000}}) {
      std::vector<Vec3> points;
      for (std::size_t i = 0; i < n; ++i) {
        points.push_back(test::randomPoint(rng, Aabb{Vec3::Constant(-5), Vec3::Constant(5)}));
      }
      std::vector<double> out(n, 12345.0);
      tree.values(points, out);
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(out[i], tree.value(points[i])) << t;
    }
  }
  std::vector<double> empty(1);
  CsgTree().values(std::vector<Vec3>{Vec3::Zero()}, empty);
  EXPECT_EQ(empty[0], -std::numeric_limits<double>::infinity());
  std::vector<double> tooShort(1);
  EXPECT_THROW(plateWithHoles().values(std::vector<Vec3>(2), tooShort), std::invalid_argument);
}

// From 4096 points on, values() splits the points among threads: the values
// are those of one thread, and of value() point by point, on any number.
TEST(TreeEvaluation, LargeBatchesGiveTheSameValuesOnAnyNumberOfThreads) {
  Rng rng(23);
  for (int t = 0; t < 4; ++t) {
    const CsgTree tree = test::randomTree(rng, 3 + 2 * t);
    std::vector<Vec3> points;
    for (std::size_t i = 0; i < 20000 + 77 * std::size_t(t); ++i) {
      points.push_back(test::randomPoint(rng, Aabb{Vec3::Constant(-5), Vec3::Constant(5)}));
    }
    std::vector<double> one(points.size()), many(points.size(), 12345.0);
    {
      const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      tree.values(points, one);
    }
    {
      const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
      tree.values(points, many);
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      ASSERT_EQ(many[i], one[i]) << t << " " << i;
      ASSERT_EQ(many[i], tree.value(points[i])) << t << " " << i;
    }
  }
}

// ---------------------------------------------------------------------------
// Restriction of a program to a region.

TEST(TreeProgram, RestrictedProgramsAreExactBelowTheirThreshold) {
  Rng rng(24);
  std::size_t exact = 0, clamped = 0;
  for (int t = 0; t < 60; ++t) {
    const CsgTree tree = test::randomTree(rng, 2 + t % 12);
    const TreeProgram full(tree);
    for (int r = 0; r < 10; ++r) {
      const Vec3 c = test::randomPoint(rng, Aabb{Vec3::Constant(-4), Vec3::Constant(4)});
      const Vec3 half(test::uniform(rng, 0.05, 1.5), test::uniform(rng, 0.05, 1.5),
                      test::uniform(rng, 0.05, 1.5));
      const Aabb region{c - half, c + half};
      const double threshold = test::uniform(rng, 0.05, 1.0);
      const TreeProgram local = full.restricted(region, threshold);
      EXPECT_LE(local.leafCount(), full.leafCount());
      // A second restriction with a lower threshold keeps the promise too.
      const TreeProgram inner = local.restricted(region, 0.5 * threshold);
      for (int i = 0; i < 200; ++i) {
        const Vec3 p = test::randomPoint(rng, region);
        const double f = full.value(p);
        const double g = local.value(p);
        if (std::abs(f) < threshold) {
          ASSERT_EQ(g, f);
          const FieldValue a = local.evaluate(p), b = tree.evaluate(p);
          ASSERT_EQ(a.f, b.f);
          ASSERT_EQ(a.gradient, b.gradient);
          ++exact;
        } else {
          ASSERT_GE(std::abs(g), threshold) << f << " " << g;
          ASSERT_EQ(g > 0.0, f > 0.0);
          ++clamped;
        }
        const double h = inner.value(p);
        if (std::abs(f) < 0.5 * threshold) {
          ASSERT_EQ(h, f);
        } else {
          ASSERT_GE(std::abs(h), 0.5 * threshold);
          ASSERT_EQ(h > 0.0, f > 0.0);
        }
      }
    }
  }
  EXPECT_GT(exact, 1000u);  // both branches were exercised
  EXPECT_GT(clamped, 1000u);
}

TEST(TreeProgram, RestrictionKeepsOnlyTheLeavesNearTheRegion) {
  // A union of 1000 unit-spaced small spheres minus a slab: near one sphere
  // only that sphere and the slab matter.
  std::vector<CsgTree> spheres;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      for (int k = 0; k < 10; ++k) spheres.push_back(CsgTree::leaf(Sphere{Vec3(i, j, k), 0.3}));
    }
  }
  const CsgTree tree = CsgTree::subtract(
      {CsgTree::unite(spheres),
       CsgTree::leaf(Box{Vec3(4.5, 4.5, 20), Mat3::Identity(), Vec3(10, 10, 10.2)})});
  const TreeProgram full(tree);
  EXPECT_EQ(full.leafCount(), 1001u);
  const Aabb nearOne{Vec3(2.8, 3.8, 4.8), Vec3(3.2, 4.2, 5.2)};
  const TreeProgram local = full.restricted(nearOne, 0.2);
  EXPECT_EQ(local.leafCount(), 1u);  // the slab is far above: only the sphere at (3, 4, 5)
  const Aabb atTheSlab{Vec3(2.8, 3.8, 9.3), Vec3(3.2, 4.2, 9.7)};  // sphere top and slab
  EXPECT_EQ(full.restricted(atTheSlab, 0.2).leafCount(), 2u);
  // Far from everything: a constant.
  const TreeProgram empty = full.restricted(Aabb{Vec3(30, 30, 30), Vec3(31, 31, 31)}, 0.5);
  EXPECT_TRUE(empty.isConstant());
  EXPECT_EQ(empty.value(Vec3(30.5, 30.5, 30.5)), -0.5);
  EXPECT_THROW(full.restricted(nearOne, 0.0), std::invalid_argument);
  EXPECT_THROW(local.restricted(nearOne, 0.3), std::invalid_argument);  // above its own
  EXPECT_THROW(full.restricted(Aabb{}, 1.0), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Leaf payloads, subtree replacement and structural hashing.

TEST(CsgTreeNodes, OperationNodesCarryNoPrimitive) {
  // A node is smaller than the primitive it may refer to: it cannot hold one.
  EXPECT_LT(sizeof(Node), sizeof(Primitive));
  const CsgTree leaf = CsgTree::leaf(Sphere{Vec3(1, 2, 3), 4}, "ball");
  EXPECT_EQ(leaf.root()->primitive, Primitive(Sphere{Vec3(1, 2, 3), 4}));
  EXPECT_EQ(leaf.root()->name, "ball");
  const CsgTree u = CsgTree::unite({leaf, leaf});
  EXPECT_EQ(u.root()->name, "");
  EXPECT_THROW(Node(NodeKind::Primitive, {}), std::invalid_argument);
}

TEST(CsgTreeEdits, ReplaceSubtreeByPathSharesTheRest) {
  const CsgTree t = plateWithHoles();  // difference(union(plate, boss), hole1, hole2, hole3)
  const CsgTree peg = CsgTree::leaf(Cylinder{Vec3(0, 1, 0), Vec3::UnitZ(), 0.2, 2}, "peg");
  const CsgTree edited = t.replaceSubtree(NodePath{2}, peg);
  EXPECT_EQ(edited.root()->children[2], peg.root());
  EXPECT_EQ(edited.root()->children[0], t.root()->children[0]);  // shared, not copied
  EXPECT_EQ(edited.root()->children[1], t.root()->children[1]);
  EXPECT_EQ(edited.root()->children[3], t.root()->children[3]);
  EXPECT_EQ(edited.root()->kind, NodeKind::Difference);
  EXPECT_EQ(t.nodeAt(NodePath{2})->name, "hole2");  // the original is unchanged
  // Deeper: the boss inside the union; the plate stays shared.
  const CsgTree boss2 = t.replaceSubtree(NodePath{0, 1}, peg);
  EXPECT_EQ(boss2.nodeAt(NodePath{0, 1}), peg.root());
  EXPECT_EQ(boss2.nodeAt(NodePath{0, 0}), t.nodeAt(NodePath{0, 0}));
  EXPECT_NE(boss2.nodeAt(NodePath{0}), t.nodeAt(NodePath{0}));
  EXPECT_EQ(boss2.primitiveCount(), t.primitiveCount());
  // The root itself.
  EXPECT_EQ(t.replaceSubtree(NodePath{}, peg).root(), peg.root());
  EXPECT_THROW(t.replaceSubtree(NodePath{4}, peg), std::out_of_range);
  EXPECT_THROW(t.replaceSubtree(NodePath{0, 0, 0}, peg), std::out_of_range);
  EXPECT_THROW(t.replaceSubtree(NodePath{1}, CsgTree()), std::invalid_argument);
  EXPECT_THROW(CsgTree().nodeAt(NodePath{}), std::out_of_range);
}

TEST(CsgTreeEdits, ReplaceSubtreeByNodeReplacesEveryUse) {
  const CsgTree a = CsgTree::leaf(Sphere{Vec3::Zero(), 1}, "a");
  const CsgTree b = CsgTree::leaf(Sphere{Vec3(3, 0, 0), 1}, "b");
  const CsgTree c = CsgTree::leaf(Box{Vec3(0, 3, 0), Mat3::Identity(), Vec3(1, 1, 1)}, "c");
  const CsgTree shared = CsgTree::unite({a, b});
  const CsgTree t = CsgTree::subtract({CsgTree::intersect({shared, c}), shared});
  const CsgTree r = t.replaceSubtree(a.root().get(), c);
  EXPECT_TRUE(r == CsgTree::subtract(
                       {CsgTree::intersect({CsgTree::unite({c, b}), c}), CsgTree::unite({c, b})}));
  EXPECT_EQ(r.nodeAt(NodePath{0, 1}), c.root());
  EXPECT_THROW(t.replaceSubtree(CsgTree::leaf(Sphere{}).root().get(), c), std::invalid_argument);
  EXPECT_THROW(t.replaceSubtree(nullptr, c), std::invalid_argument);
}

// Rebuilds a tree node by node (no sharing with the original), renaming leaves.
CsgTree deepCopy(const Node& n) {
  if (n.kind == NodeKind::Primitive) return CsgTree::leaf(n.primitive, n.name + "_copy");
  std::vector<CsgTree> children;
  for (const NodePtr& c : n.children) children.push_back(deepCopy(*c));
  switch (n.kind) {
    case NodeKind::Union:
      return CsgTree::unite(children);
    case NodeKind::Intersection:
      return CsgTree::intersect(children);
    case NodeKind::Difference:
      return CsgTree::subtract(children);
    default:
      return CsgTree::complement(children.front());
  }
}

TEST(CsgTreeHashing, EqualTreesHashEqualAndDifferentOnesRarelyCollide) {
  Rng rng(25);
  std::vector<CsgTree> trees;
  for (int t = 0; t < 300; ++t) trees.push_back(test::randomTree(rng, 1 + t % 10));
  std::unordered_map<CsgTree, int, CsgTreeHash> cache;
  for (std::size_t i = 0; i < trees.size(); ++i) {
    const CsgTree copy = deepCopy(*trees[i].root());
    ASSERT_NE(copy.root(), trees[i].root());
    ASSERT_TRUE(copy == trees[i]);
    EXPECT_EQ(copy.structuralHash(), trees[i].structuralHash());
    cache[trees[i]] = static_cast<int>(i);
    EXPECT_EQ(cache.at(copy), static_cast<int>(i));  // a copy finds the cached entry
    // Replacing any subtree by itself gives an equal tree, hash included.
    const std::vector<const Node*> leaves = trees[i].leaves();
    const Node* leaf = leaves[i % leaves.size()];
    const CsgTree same = trees[i].replaceSubtree(leaf, CsgTree::leaf(leaf->primitive));
    EXPECT_EQ(same.structuralHash(), trees[i].structuralHash());
    // Moving one leaf by a hair changes the tree and, here, its hash.
    Primitive moved = leaf->primitive;
    if (const auto* s = moved.as<Sphere>()) {
      moved = Sphere{s->center + Vec3(1e-12, 0, 0), s->radius};
    } else {
      moved = Sphere{Vec3(1, 2, 3), 0.5};
    }
    const CsgTree other = trees[i].replaceSubtree(leaf, CsgTree::leaf(moved));
    EXPECT_FALSE(other == trees[i]);
    EXPECT_NE(other.structuralHash(), trees[i].structuralHash());
  }
  // Distinct trees: pairwise, equal hashes only for equal trees (no collision
  // among these 300).
  std::size_t collisions = 0;
  for (std::size_t i = 0; i < trees.size(); ++i) {
    for (std::size_t j = i + 1; j < trees.size(); ++j) {
      const bool equal = trees[i] == trees[j];
      const bool sameHash = trees[i].structuralHash() == trees[j].structuralHash();
      if (equal) {
        EXPECT_TRUE(sameHash);
      }
      collisions += sameHash && !equal;
    }
  }
  EXPECT_EQ(collisions, 0u);
  // Order, kind and arity matter; names and the sign of zero do not.
  const CsgTree a = CsgTree::leaf(Sphere{Vec3(0.0, 1, 2), 1}, "a");
  const CsgTree a0 = CsgTree::leaf(Sphere{Vec3(-0.0, 1, 2), 1}, "other name");
  const CsgTree b = CsgTree::leaf(Sphere{Vec3(1, 1, 2), 1});
  EXPECT_TRUE(a == a0);
  EXPECT_EQ(a.structuralHash(), a0.structuralHash());
  EXPECT_NE(CsgTree::unite({a, b}).structuralHash(), CsgTree::unite({b, a}).structuralHash());
  EXPECT_NE(CsgTree::unite({a, b}).structuralHash(), CsgTree::intersect({a, b}).structuralHash());
  EXPECT_NE(CsgTree::unite({a}).structuralHash(), a.structuralHash());
  EXPECT_EQ(CsgTree().structuralHash(), 0u);
}

}  // namespace
}  // namespace csgvox
