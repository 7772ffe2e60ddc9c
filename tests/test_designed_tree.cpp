// The designed tree: frame, snapped parameters, shared groups and patterns,
// on the bundled parts' true trees moved and perturbed as a fit leaves them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "design/designed_tree.h"
#include "design/part_frame.h"
#include "design/value_ladder.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::dataDir;

CsgTree part(const std::string& name) { return readTreeJson(dataDir() / name / "tree.json"); }

// Every length of every primitive moved by up to `noise` (a fit's error).
CsgTree perturbed(const CsgTree& tree, double noise, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-noise, noise);
  std::unordered_map<const Node*, NodePtr> done;
  std::function<NodePtr(const NodePtr&)> walk = [&](const NodePtr& n) -> NodePtr {
    if (auto it = done.find(n.get()); it != done.end()) return it->second;
    NodePtr out;
    if (n->kind == NodeKind::Primitive) {
      Primitive p = std::visit(
          [&](auto s) -> Primitive {
            using T = decltype(s);
            if constexpr (std::is_same_v<T, HalfSpace>) {
              s.offset += u(rng);
            } else {
              s.center += Vec3(u(rng), u(rng), u(rng));
              if constexpr (std::is_same_v<T, Box>) s.halfSize += Vec3(u(rng), u(rng), u(rng));
              if constexpr (std::is_same_v<T, Cylinder>) s.radius += u(rng), s.height += u(rng);
              if constexpr (std::is_same_v<T, Sphere>) s.radius += u(rng);
              if constexpr (std::is_same_v<T, Torus>)
                s.majorRadius += u(rng), s.minorRadius += u(rng);
              if constexpr (std::is_same_v<T, Cone>) {
                s.radiusBottom += s.radiusBottom > 0 ? u(rng) : 0.0;
                s.radiusTop += s.radiusTop > 0 ? u(rng) : 0.0;
                s.height += u(rng);
              }
            }
            return s;
          },
          n->primitive.shape());
      out = std::make_shared<const Node>(p, n->name);
    } else {
      std::vector<NodePtr> c;
      for (const auto& k : n->children) c.push_back(walk(k));
      out = std::make_shared<const Node>(n->kind, c);
    }
    return done[n.get()] = out;
  };
  return CsgTree(walk(tree.root()));
}

// Parameter name -> designed value.
std::map<std::string, double> valuesOf(const DesignedTree& d) {
  std::map<std::string, double> out;
  for (const DesignParameter& p : d.parameters) out[p.name] = p.value;
  return out;
}

bool hasValue(const DesignedTree& d, double v) {
  return std::any_of(d.parameters.begin(), d.parameters.end(),
                     [&](const DesignParameter& p) { return p.value == v; });
}

TEST(ValueLadder, TakesTheCoarsestStepWithinTheUncertainty) {
  EXPECT_EQ(*simplestLength(33.9997, 0.001, UnitSystem::Millimetre), 34.0);
  EXPECT_EQ(*simplestLength(12.4996, 0.001, UnitSystem::Millimetre), 12.5);
  EXPECT_EQ(*simplestLength(0.29996, 0.001, UnitSystem::Millimetre), 0.3);
  EXPECT_EQ(*simplestLength(7.0312, 0.002, UnitSystem::Millimetre), 7.03);
  EXPECT_FALSE(simplestLength(7.0345, 0.0001, UnitSystem::Millimetre));
  EXPECT_EQ(*simplestLength(-1.77, std::numeric_limits<double>::infinity(), UnitSystem::Millimetre),
            -2.0);
  EXPECT_DOUBLE_EQ(*simplestLength(12.71, 0.02, UnitSystem::Inch), 12.7);
  EXPECT_EQ(*simplestAngle(29.9999, 0.001), 30.0);
  EXPECT_EQ(*simplestAngle(-31.37, 0.4), -31.0);
  // A step finer than twice the uncertainty always has a multiple within it:
  // rounding to it would find nothing, so the ladder stops above it.
  EXPECT_FALSE(simplestAngle(-31.37, 0.5));
  EXPECT_FALSE(simplestLength(44.915, 0.072, UnitSystem::Millimetre));
  EXPECT_EQ(*simplestLength(44.915, 0.09, UnitSystem::Millimetre), 45.0);
  EXPECT_EQ(*simplestLength(44.915, 0.04, UnitSystem::Millimetre), 44.9);
  EXPECT_FALSE(simplestLength(5.65685, 0.1, UnitSystem::Millimetre));
  EXPECT_EQ(inchText(31.75), "1 1/4 in");
  EXPECT_EQ(inchText(3.175), "1/8 in");
  EXPECT_EQ(inchText(10.0), "");
}

// The flange as a fit leaves it: every designed radius exact, the six bolt
// holes one circular pattern, the designed tree the fitted one's shape.
TEST(DesignedTree, FlangeBoltHolesAreOneCircle) {
  const DesignedTree d = designTree(perturbed(part("flange"), 1e-4, 1));
  ASSERT_EQ(d.patterns.size(), 1u);
  const DesignedPattern& p = d.patterns.front();
  EXPECT_EQ(p.kind, PatternKind::Circular);
  EXPECT_EQ(p.members.size(), 6u);
  EXPECT_EQ(p.radius.value(d.parameters), 38.0);
  EXPECT_EQ(d.parameters[std::size_t(p.count)].value, 6.0);
  for (double r : {50.0, 25.0, 15.0, 5.0, 31.0, 6.0}) EXPECT_TRUE(hasValue(d, r)) << r;
  EXPECT_GE(d.iouToFitted, 0.999);
  EXPECT_GE(test::treeIou(d.tree(), part("flange")), 0.999);
}

// A turned and moved copy of a part gives the same parameters, and the
// designed tree lies where the copy does.
TEST(DesignedTree, RotatedPartGivesTheSameParameters) {
  for (const std::string name : {"flange", "plate_holes", "l_bracket", "bearing_housing"}) {
    SCOPED_TRACE(name);
    const CsgTree fitted = perturbed(part(name), 1e-5, 2);
    test::Rng rng(5);
    const Mat3 r = test::randomRotation(rng);
    const CsgTree turned = transformedTree(fitted, r, Vec3(12.5, -40.0, 7.0));
    const DesignedTree a = designTree(fitted), b = designTree(turned);
    const auto va = valuesOf(a), vb = valuesOf(b);
    ASSERT_EQ(va.size(), vb.size());
    std::vector<double> sa, sb;
    for (const auto& [k, v] : va) sa.push_back(v);
    for (const auto& [k, v] : vb) sb.push_back(v);
    std::sort(sa.begin(), sa.end());
    std::sort(sb.begin(), sb.end());
    for (std::size_t i = 0; i < sa.size(); ++i) EXPECT_NEAR(sa[i], sb[i], 1e-5) << i;
    EXPECT_GE(test::treeIou(b.tree(), turned), 0.995);
  }
}

TEST(DesignedTree, PlateHolesAreOneLattice) {
  const DesignedTree d = designTree(perturbed(part("plate_holes"), 1e-4, 3));
  ASSERT_EQ(d.patterns.size(), 1u);
  EXPECT_EQ(d.patterns.front().members.size(), 4u);
  EXPECT_NE(d.patterns.front().kind, PatternKind::Circular);
}

// On every bundled part, fitted to 1e-5: every radius of the true tree on
// the ladder's finest grid (hundredths; the knob's dome has 43.0625) is a
// parameter's value, exactly, and the designed tree keeps the fitted one's
// shape.
TEST(DesignedTree, BundledPartsKeepTheirRadiiExactly) {
  DesignOptions o;
  o.treeUncertainty = 1e-4;
  const auto onGrid = [](double v) { return std::abs(v * 100 - std::round(v * 100)) < 1e-9; };
  for (const std::string& name : test::partNames()) {
    SCOPED_TRACE(name);
    const CsgTree truth = part(name);
    const DesignedTree d = designTree(perturbed(truth, 1e-5, 4), {}, o);
    EXPECT_GE(d.iouToFitted, 0.999);
    for (const Node* leaf : truth.leaves()) {
      if (!onGrid(leaf->primitive.as<Cylinder>() ? leaf->primitive.as<Cylinder>()->radius
                  : leaf->primitive.as<Sphere>() ? leaf->primitive.as<Sphere>()->radius
                                                 : 0.0)) {
        continue;
      }
      if (const auto* c = leaf->primitive.as<Cylinder>()) {
        EXPECT_TRUE(hasValue(d, c->radius)) << leaf->name << " " << c->radius;
      }
      if (const auto* s = leaf->primitive.as<Sphere>()) {
        EXPECT_TRUE(hasValue(d, s->radius)) << leaf->name << " " << s->radius;
      }
    }
  }
}

// The snap is refused when it would change the solid: a 10.4 wide block
// with a loose uncertainty keeps its width (10 would lose 4 % of it).
TEST(DesignedTree, RefusesASnapThatChangesTheSolid) {
  const CsgTree block = CsgTree::leaf(Box{Vec3(0, 0, 0), Mat3::Identity(), Vec3(5.2, 7, 3)});
  DesignOptions o;
  o.treeUncertainty = 0.05;  // 0.05 of D: 10 lies within it
  const DesignedTree d = designTree(block, {}, o);
  EXPECT_FALSE(hasValue(d, 5.0) && hasValue(d, -5.0));
  EXPECT_GE(d.iouToFitted, 0.999);
  EXPECT_TRUE(test::treesEquivalent(d.tree(), block, 4000, 1));
}

// With scan points, a value the points hold tightly keeps its digits and
// one no point holds (a hole's end past the part) snaps.
TEST(DesignedTree, PointsSetTheUncertainty) {
  const Cylinder plate{Vec3(0, 0, 5), Vec3::UnitZ(), 40.3, 10};
  const Cylinder hole{Vec3(0, 0, 4.77), Vec3::UnitZ(), 8, 11.54};  // ends at 10.54 and -1
  const CsgTree tree = CsgTree::subtract({CsgTree::leaf(plate), CsgTree::leaf(hole)});
  std::vector<Vec3> points;
  for (const Vec3& p : test::sampleSurface(plate, 1.0).points) {
    if (std::abs(tree.value(p)) < 1e-9) points.push_back(p);
  }
  for (const Vec3& p : test::sampleSurface(hole, 1.0).points) {
    if (std::abs(tree.value(p)) < 1e-9) points.push_back(p);
  }
  const DesignedTree d = designTree(tree, points);
  EXPECT_TRUE(hasValue(d, 40.3));
  EXPECT_TRUE(hasValue(d, 8.0));
  EXPECT_TRUE(hasValue(d, 11.0)) << "the hole's top past the plate snaps to a whole unit";
  EXPECT_GE(d.iouToFitted, 0.999);
}

// A noisy scan's datum face fitted 0.04 off (x = 40: the frame's x runs
// from the hole's side, and its origin is that corner of the bounds): the
// snapped sizes measured from it would carry the whole error to the far
// faces. The origin moves to where the snapped
// positions put it, and the designed block lies nearer the true one than
// the fitted block does.
TEST(DesignedTree, OriginMovesToWhereTheSnappedPositionsPutIt) {
  const Box truthBlock{Vec3(20, 15, 5), Mat3::Identity(), Vec3(20, 15, 5)};  // [0,40]x[0,30]x[0,10]
  const Cylinder hole{Vec3(12, 15, 5), Vec3::UnitZ(), 4, 14};
  const CsgTree truth = CsgTree::subtract({CsgTree::leaf(truthBlock), CsgTree::leaf(hole)});
  const Box fittedBlock{Vec3(20.02, 15, 5), Mat3::Identity(), Vec3(20.02, 15, 5)};  // x to 40.04
  const CsgTree fitted = CsgTree::subtract({CsgTree::leaf(fittedBlock), CsgTree::leaf(hole)});
  test::Rng rng(7);
  std::normal_distribution<double> noise(0.0, 0.25);
  std::vector<Vec3> points;
  for (const Primitive& p : {Primitive(truthBlock), Primitive(hole)}) {
    for (const Vec3& q : test::sampleSurface(p, 2.0).points) {
      if (std::abs(truth.value(q)) < 1e-9) {
        points.push_back(q + Vec3(noise(rng), noise(rng), noise(rng)));
      }
    }
  }
  const DesignedTree d = designTree(fitted, points);
  const Aabb box = d.tree().root()->children.front()->primitive.bounds();
  EXPECT_LT(std::abs(box.min.x() - 0.0), 0.03);
  EXPECT_LT(std::abs(box.max.x() - 40.0), 0.03);
  EXPECT_GT(test::treeIou(d.tree(), truth), test::treeIou(fitted, truth));
}

// Values no point holds (three pockets' walls, their points removed) snap
// only when the solid keeps its shape: each 0.04 move costs less than the
// 0.001 of IoU a held value may, but nothing says the whole unit is right.
TEST(DesignedTree, AValueNoPointHoldsDoesNotChangeTheSolid) {
  const Box block{Vec3(20, 15, 5), Mat3::Identity(), Vec3(20, 15, 5)};  // [0,40]x[0,30]x[0,10]
  std::vector<CsgTree> parts = {CsgTree::leaf(block)};
  std::vector<Aabb> pockets;
  for (const auto& [x0, x1] : {std::pair{10.04, 15.0}, {20.04, 24.0}, {30.04, 33.0}}) {
    const Aabb b{Vec3(x0, -1, 6), Vec3(x1, 31, 11)};
    pockets.push_back(b);
    parts.push_back(CsgTree::leaf(Box{b.center(), Mat3::Identity(), 0.5 * b.size()}));
  }
  const CsgTree tree = CsgTree::subtract(std::move(parts));
  std::vector<Vec3> points;
  for (const Vec3& q : test::sampleSurface(block, 0.5).points) {
    const bool nearPocket = std::any_of(pockets.begin(), pockets.end(),
                                        [&](const Aabb& b) { return b.grown(2.0).contains(q); });
    if (!nearPocket && std::abs(tree.value(q)) < 1e-9) points.push_back(q);
  }
  const DesignedTree d = designTree(tree, points);
  for (double wall : {10.04, 20.04, 30.04}) EXPECT_TRUE(hasValue(d, wall)) << wall;
  EXPECT_TRUE(hasValue(d, 40.0));
  EXPECT_GE(d.iouToFitted, 0.9999);
}

// The points of `truth` on its surface, sampled at `step` from the
// leaves, moved along each axis by N(0, noise).
std::vector<Vec3> scanOf(const CsgTree& truth, double step, double noise, unsigned seed) {
  test::Rng rng(seed);
  std::normal_distribution<double> n(0.0, noise);
  std::vector<Vec3> points;
  for (const Node* leaf : truth.distinctLeaves()) {
    for (const Vec3& q : test::sampleSurface(leaf->primitive, step).points) {
      if (std::abs(truth.value(q)) < 1e-9) points.push_back(q + Vec3(n(rng), n(rng), n(rng)));
    }
  }
  return points;
}

CsgTree boxLeaf(const Aabb& b) {
  return CsgTree::leaf(Box{b.center(), Mat3::Identity(), 0.5 * b.size()});
}

// A tray with 1 wide walls scanned with noise 0.2: its pocket's faces,
// fitted 0.03-0.04 off, have 1 and 59 well within their uncertainty, yet
// each snap costs the thin solid 0.002-0.004 of IoU, more than the 0.001
// a value may cost alone. Moving the face by its uncertainty costs more
// than that: the fitted value is no surer, and the snaps are kept.
TEST(DesignedTree, ThinWallsSnapWithinTheirUncertainty) {
  const Aabb outer{Vec3(0, 0, 0), Vec3(60, 40, 10)}, pocket{Vec3(1, 1, 1), Vec3(59, 39, 11)};
  const CsgTree truth = CsgTree::subtract({boxLeaf(outer), boxLeaf(pocket)});
  const CsgTree fitted = CsgTree::subtract(
      {boxLeaf(outer), boxLeaf(Aabb{Vec3(1.04, 0.97, 1.0), Vec3(58.97, 39.03, 11)})});
  const DesignedTree d = designTree(fitted, scanOf(truth, 1.5, 0.2, 3));
  for (double v : {1.0, 59.0, 39.0}) EXPECT_TRUE(hasValue(d, v)) << v;
  for (double v : {1.04, 0.97, 58.97, 39.03}) EXPECT_FALSE(hasValue(d, v)) << v;
  EXPECT_GT(test::treeIou(d.tree(), truth), test::treeIou(fitted, truth));
}

// A turned part whose faces leave x free and has no bolt circle: x runs
// along its radial hole (a knob's set screw), which is then written with
// parameters (its radius exact), and a turned copy gives the same values.
TEST(DesignedTree, RadialHoleSetsTheTurnedPartsX) {
  const double a = 0.5;  // the screw's direction, radians from the world's x
  const Vec3 dir(std::cos(a), std::sin(a), 0.0);
  const CsgTree knob =
      CsgTree::subtract({CsgTree::leaf(Cylinder{Vec3(0, 0, 18), Vec3::UnitZ(), 25, 36}),
                         CsgTree::leaf(Cylinder{Vec3(0, 0, 10), Vec3::UnitZ(), 6, 24}),
                         CsgTree::leaf(Cylinder{Vec3(0, 0, 10) + 17.0 * dir, dir, 2, 18})});
  const CsgTree fitted = perturbed(knob, 1e-5, 6);
  const std::vector<Vec3> points = scanOf(knob, 1.0, 0.0, 1);
  const DesignedTree d = designTree(fitted, points);
  for (const DesignedLeaf& l : d.leaves) EXPECT_NE(l.form, LeafForm::Free) << l.name;
  EXPECT_TRUE(hasValue(d, 2.0));
  test::Rng rng(9);
  const Mat3 r = test::randomRotation(rng);
  const Vec3 t(5, -3, 11);
  std::vector<Vec3> moved;
  for (const Vec3& p : points) moved.push_back(r * p + t);
  const DesignedTree e = designTree(transformedTree(fitted, r, t), moved);
  const auto vd = valuesOf(d), ve = valuesOf(e);
  ASSERT_EQ(vd.size(), ve.size());
  for (const auto& [name, v] : vd) {
    ASSERT_TRUE(ve.count(name)) << name;
    EXPECT_NEAR(ve.at(name), v, 1e-5) << name;
  }
}

// A cone fitted to stop short of its tip (radius 0.05, where a scan's
// points thin out) runs on to its apex: the designed cone is drawn to a
// point at the true height.
TEST(DesignedTree, ConeTipRunsOnToItsApex) {
  const Cone tip{Vec3(0, 0, 25), Vec3::UnitZ(), 5.0, 0.0, 10.0};  // z 20..30
  const CsgTree truth = CsgTree::unite(
      {CsgTree::leaf(Box{Vec3(0, 0, 10), Mat3::Identity(), Vec3(10, 10, 10)}), CsgTree::leaf(tip)});
  const CsgTree fitted = CsgTree::unite(
      {CsgTree::leaf(Box{Vec3(0, 0, 10), Mat3::Identity(), Vec3(10, 10, 10)}),
       CsgTree::leaf(Cone{Vec3(0, 0, 24.95), Vec3::UnitZ(), 5.0, 0.05, 9.9})});  // z 20..29.9
  const DesignedTree d = designTree(fitted, scanOf(truth, 0.5, 0.02, 4));
  const CsgTree designed = d.tree();
  const Node* cone = nullptr;
  for (const Node* leaf : designed.leaves()) {
    if (leaf->primitive.as<Cone>()) cone = leaf;
  }
  ASSERT_NE(cone, nullptr);
  const Cone& c = *cone->primitive.as<Cone>();
  EXPECT_EQ(std::min(c.radiusBottom, c.radiusTop), 0.0);
  EXPECT_NEAR(c.center.z() + 0.5 * c.height, 30.0, 1e-9);
  EXPECT_TRUE(hasValue(d, 30.0));
}

// A clean scan's face a fit left 0.45 off its points (a slot's end): no
// point lies within the noise band of it, but those near it all say where
// it is, and it snaps there (the nearest whole unit of the fitted value
// would be wrong, and changes the solid).
TEST(DesignedTree, AFaceOffItsPointsTakesTheirValue) {
  const Aabb plate{Vec3(0, 0, 0), Vec3(40, 30, 10)}, slot{Vec3(10, 5, 4), Vec3(14, 25, 11)};
  const CsgTree truth = CsgTree::subtract({boxLeaf(plate), boxLeaf(slot)});
  const CsgTree fitted =
      CsgTree::subtract({boxLeaf(plate), boxLeaf(Aabb{Vec3(10, 5, 4), Vec3(14, 25.45, 11)})});
  const DesignedTree d = designTree(fitted, scanOf(truth, 0.5, 0.0, 2));
  EXPECT_TRUE(hasValue(d, 25.0));
  EXPECT_FALSE(hasValue(d, 25.45));
  EXPECT_TRUE(test::treesEquivalent(d.tree(), truth, 4000, 1));
}

TEST(DesignedTree, RoleNames) {
  const DesignedTree d = designTree(part("flange"));
  std::set<std::string> roles;
  for (const DesignedLeaf& l : d.leaves) roles.insert(l.role);
  EXPECT_TRUE(roles.count("hole"));
  EXPECT_TRUE(roles.count("bore"));
  EXPECT_TRUE(roles.count("hub"));
  EXPECT_TRUE(roles.count("fillet"));
}

}  // namespace
}  // namespace csgvox
