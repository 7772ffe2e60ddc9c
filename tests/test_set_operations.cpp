// Tests for primitives/set_operations.h: min/max and R-function operations
// keep the same zero set, their values follow the closed forms and their
// gradients match finite differences.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/csg_tree.h"
#include "core/set_operations.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::Rng;

FieldValue randomField(Rng& rng) {
  FieldValue v;
  // A mix of scales, with exact zeros now and then.
  const int kind = std::uniform_int_distribution<int>(0, 9)(rng);
  v.f = kind == 0 ? 0.0 : test::uniform(rng, -2, 2) * std::pow(10.0, test::uniform(rng, -3, 1));
  v.gradient = test::randomUnit(rng);
  return v;
}

FieldValue field(double f, const Vec3& g) { return FieldValue{f, g}; }

TEST(SetOperations, KindsAndNames) {
  EXPECT_EQ(&setOperations(SetOperationKind::MinMax), &minMaxOperations());
  EXPECT_EQ(&setOperations(SetOperationKind::RFunction), &rFunctionOperations());
  EXPECT_EQ(minMaxOperations().name(), "minmax");
  EXPECT_EQ(rFunctionOperations().name(), "rfunction");
  EXPECT_EQ(minMaxOperations().kind(), SetOperationKind::MinMax);
  EXPECT_EQ(rFunctionOperations().kind(), SetOperationKind::RFunction);
}

TEST(SetOperations, ValueOnlyFormsGiveTheSameValuesBitForBit) {
  Rng rng(11);
  for (int i = 0; i < 10000; ++i) {
    FieldValue a = randomField(rng), b = randomField(rng);
    if (i % 10 == 0) b.f = a.f;     // ties
    if (i % 10 == 1) a.f = 0.0;     // zero operands
    if (i % 10 == 2) b.f = -1e200;  // far values
    ASSERT_EQ(MinMaxValues::unite(a.f, b.f), minMaxOperations().unite(a, b).f);
    ASSERT_EQ(MinMaxValues::intersect(a.f, b.f), minMaxOperations().intersect(a, b).f);
    ASSERT_EQ(RFunctionValues::unite(a.f, b.f), rFunctionOperations().unite(a, b).f);
    ASSERT_EQ(RFunctionValues::intersect(a.f, b.f), rFunctionOperations().intersect(a, b).f);
  }
}

TEST(MinMaxOperations, AreMinAndMaxWithTheWinnersGradient) {
  const SetOperations& ops = minMaxOperations();
  Rng rng(1);
  for (int i = 0; i < 1000; ++i) {
    const FieldValue a = randomField(rng), b = randomField(rng);
    const FieldValue in = ops.intersect(a, b), un = ops.unite(a, b);
    EXPECT_EQ(in.f, std::min(a.f, b.f));
    EXPECT_EQ(un.f, std::max(a.f, b.f));
    if (a.f != b.f) {
      test::expectNear(in.gradient, a.f < b.f ? a.gradient : b.gradient, 0.0);
      test::expectNear(un.gradient, a.f > b.f ? a.gradient : b.gradient, 0.0);
    }
  }
}

TEST(RFunctionOperations, ClosedForms) {
  const SetOperations& ops = rFunctionOperations();
  const Vec3 ga(1, 0, 0), gb(0, 1, 0);
  // f1 + f2 -/+ sqrt(f1^2 + f2^2) with (3, 4): hypot 5.
  EXPECT_DOUBLE_EQ(ops.intersect(field(3, ga), field(4, gb)).f, 2.0);
  EXPECT_DOUBLE_EQ(ops.unite(field(3, ga), field(4, gb)).f, 12.0);
  EXPECT_DOUBLE_EQ(ops.intersect(field(-3, ga), field(4, gb)).f, -4.0);
  EXPECT_DOUBLE_EQ(ops.unite(field(-3, ga), field(-4, gb)).f, -2.0);
  EXPECT_DOUBLE_EQ(ops.unite(field(0, ga), field(-4, gb)).f, 0.0);
  EXPECT_DOUBLE_EQ(ops.intersect(field(0, ga), field(4, gb)).f, 0.0);
  // d/df1 = 1 -/+ f1 / r, d/df2 = 1 -/+ f2 / r.
  test::expectNear(ops.intersect(field(3, ga), field(4, gb)).gradient, Vec3(1 - 0.6, 1 - 0.8, 0),
                   1e-15);
  test::expectNear(ops.unite(field(3, ga), field(4, gb)).gradient, Vec3(1 + 0.6, 1 + 0.8, 0),
                   1e-15);
  // Both zero: value 0 and a finite gradient.
  const FieldValue z = ops.intersect(field(0, ga), field(0, gb));
  EXPECT_EQ(z.f, 0.0);
  EXPECT_TRUE(z.gradient.allFinite());
}

// Every implementation describes the same solid: the sign of the result is
// the sign of min (intersection) or max (union).
TEST(RFunctionOperations, SignMatchesMinMax) {
  const SetOperations& ops = rFunctionOperations();
  Rng rng(2);
  int mixed = 0;
  for (int i = 0; i < 5000; ++i) {
    const FieldValue a = randomField(rng), b = randomField(rng);
    const double mn = std::min(a.f, b.f), mx = std::max(a.f, b.f);
    const double in = ops.intersect(a, b).f, un = ops.unite(a, b).f;
    mixed += (a.f > 0) != (b.f > 0);
    EXPECT_EQ(in > 0, mn > 0) << a.f << " " << b.f;
    EXPECT_EQ(in < 0, mn < 0) << a.f << " " << b.f;
    EXPECT_EQ(un > 0, mx > 0) << a.f << " " << b.f;
    EXPECT_EQ(un < 0, mx < 0) << a.f << " " << b.f;
    // Both operands inside: the intersection is no deeper than either.
    if (a.f > 0 && b.f > 0) {
      EXPECT_LE(in, mn * (1 + 1e-12));
    }
  }
  EXPECT_GT(mixed, 1000);
}

// The combined field of two primitives and its gradient at p.
FieldValue combined(const SetOperations& ops, bool unite, const Primitive& a, const Primitive& b,
                    const Vec3& p) {
  FieldValue fa, fb;
  fa.f = a.valueAndGradient(p, fa.gradient);
  fb.f = b.valueAndGradient(p, fb.gradient);
  return unite ? ops.unite(fa, fb) : ops.intersect(fa, fb);
}

void checkGradients(const SetOperations& ops, std::uint64_t seed) {
  Rng rng(seed);
  int checked = 0, total = 0;
  for (int pair = 0; pair < 20; ++pair) {
    const Primitive a = test::randomBoundedPrimitive(rng), b = test::randomBoundedPrimitive(rng);
    Aabb box = a.bounds();
    box.extend(b.bounds());
    for (bool unite : {false, true}) {
      const auto fn = [&](const Vec3& p) { return combined(ops, unite, a, b, p).f; };
      for (int i = 0; i < 20; ++i) {
        const Vec3 p = test::randomPoint(rng, box);
        ++total;
        if (!test::isSmoothAt(fn, p, 1e-3)) continue;
        ++checked;
        const FieldValue v = combined(ops, unite, a, b, p);
        EXPECT_TRUE(test::vecNear(v.gradient, test::numericGradient(fn, p, 1e-6), 1e-5))
            << (unite ? "union" : "intersection") << " at " << test::str(p);
      }
    }
  }
  EXPECT_GE(checked, total * 9 / 10);
}

TEST(MinMaxOperations, GradientMatchesFiniteDifferences) { checkGradients(minMaxOperations(), 3); }

TEST(RFunctionOperations, GradientMatchesFiniteDifferences) {
  checkGradients(rFunctionOperations(), 4);
}

// Whole trees: the two implementations give the same solid, and complement
// and difference are built from intersection and negation for both.
TEST(SetOperations, TreesHaveTheSameZeroSetUnderEveryImplementation) {
  Rng rng(5);
  int inside = 0, outside = 0;
  for (int t = 0; t < 20; ++t) {
    const CsgTree tree = test::randomTree(rng, 2 + t % 5);
    Aabb box = tree.leaves().front()->primitive.bounds().grown(1.0);
    for (const Node* leaf : tree.leaves()) box.extend(leaf->primitive.bounds());
    for (int i = 0; i < 300; ++i) {
      const Vec3 p = test::randomPoint(rng, box);
      const double m = tree.value(p, minMaxOperations());
      const double r = tree.value(p, rFunctionOperations());
      if (std::abs(m) < 1e-9) continue;
      (m > 0 ? inside : outside)++;
      EXPECT_EQ(m > 0, r > 0) << "tree " << t << " at " << test::str(p) << ": " << m << " vs " << r;
    }
  }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 100);
}

TEST(SetOperations, DifferenceAndComplementUseNegation) {
  Rng rng(6);
  const Primitive a = Sphere{Vec3::Zero(), 1.0};
  const Primitive b = Box{Vec3(0.8, 0, 0), Mat3::Identity(), Vec3(0.5, 0.5, 0.5)};
  const CsgTree ta = CsgTree::leaf(a), tb = CsgTree::leaf(b);
  const CsgTree diff = CsgTree::subtract({ta, tb});
  const CsgTree comp = CsgTree::complement(tb);
  for (const SetOperations* ops : {&minMaxOperations(), &rFunctionOperations()}) {
    for (int i = 0; i < 200; ++i) {
      const Vec3 p = test::randomPoint(rng, Aabb{Vec3::Constant(-1.5), Vec3::Constant(1.5)});
      FieldValue fa, fb;
      fa.f = a.valueAndGradient(p, fa.gradient);
      fb.f = b.valueAndGradient(p, fb.gradient);
      const FieldValue nb{-fb.f, -fb.gradient};
      const FieldValue expected = ops->intersect(fa, nb);
      const FieldValue got = diff.evaluate(p, *ops);
      EXPECT_EQ(got.f, expected.f);
      test::expectNear(got.gradient, expected.gradient, 0.0);
      const FieldValue c = comp.evaluate(p, *ops);
      EXPECT_EQ(c.f, -fb.f);
      test::expectNear(c.gradient, -fb.gradient, 0.0);
    }
  }
}

}  // namespace
}  // namespace csgvox
