// Tests for primitives/csg_tree.h: counts, evaluation against an independent
// classification, bounds, structural equality, validation and the sharing of
// immutable subtrees.

#include "core/csg_tree.h"

#include "test_helpers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

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
  b = CsgTree::intersect({half, slab}).bounds();
  ASSERT_TRUE(b.isBounded());
  test::expectNear(b.min, Vec3(0.5, -2, -2), 1e-15);
  test::expectNear(b.max, Vec3(1.5, 2, 2), 1e-15);
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
    sampleBox = test::grown(sampleBox, 0.5);
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

}  // namespace
}  // namespace csgvox
