// The genetic search (evolve/genetic_search.h), its variation operators and
// redundancy removal, on the box's six face planes.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "evolve/genetic_search.h"
#include "evolve/redundancy.h"
#include "evolve_fixtures.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

constexpr double kDiagonal = 2.0 * 1.7320508075688772;

bool leavesAreTheLibrarys(const CsgTree& tree, const PrimitiveLibrary& library) {
  for (const Node* leaf : tree.leaves()) {
    bool found = false;
    for (std::size_t i = 0; i < library.size() && !found; ++i)
      found = library.leaf(i).get() == leaf;
    if (!found) return false;
  }
  return true;
}

// Same solid as the cube: every sampled point classified alike.
bool isTheCube(const CsgTree& tree) {
  for (double x = -1.45; x <= 1.5; x += 0.1) {
    for (double y = -1.45; y <= 1.5; y += 0.1) {
      for (double z = -1.45; z <= 1.5; z += 0.1) {
        const bool inCube = std::abs(x) < 1 && std::abs(y) < 1 && std::abs(z) < 1;
        if (tree.contains(Vec3(x, y, z)) != inCube) return false;
      }
    }
  }
  return true;
}

TEST(GeneticSearch, FindsTheExactCubeFromItsSixPlanes) {
  const test::OrientedPoints in = test::cubeFacePoints(30);
  const PrimitiveLibrary library = test::cubePlanes();
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  int found = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    EvolveOptions options;
    options.seed = seed;
    options.maxGenerations = 400;
    options.stallGenerations = 100;
    const EvolveResult r = evolve(model, {}, options);
    EXPECT_TRUE(leavesAreTheLibrarys(r.best, library));
    if (r.best.primitiveCount() == 6 && r.best.nodeCount() == 11 && isTheCube(r.best)) ++found;
  }
  EXPECT_GE(found, 4);
}

TEST(GeneticSearch, SameTreeForASeedWhateverTheThreads) {
  const test::OrientedPoints in = test::cubeFacePoints(16);
  const PrimitiveLibrary library =
      test::cubePlanes({Sphere{Vec3(1, 1, 1), 0.8}, Cylinder{Vec3::Zero(), Vec3::UnitZ(), 0.5, 4}});
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  EvolveOptions options;
  options.seed = 9;
  options.maxGenerations = 60;
  options.stallGenerations = 0;
  EvolveResult one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = evolve(model, {}, options);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = evolve(model, {}, options);
  }
  EXPECT_TRUE(one.best.structurallyEqual(two.best));
  EXPECT_EQ(one.fitness.total, two.fitness.total);
  EXPECT_EQ(one.evaluations, two.evaluations);
  // The seed does steer the search.
  options.seed = 10;
  const EvolveResult other = evolve(model, {}, options);
  EXPECT_TRUE(other.evaluations != one.evaluations || !other.best.structurallyEqual(one.best));
}

TEST(GeneticSearch, SeedsAreKeptAndStopRulesHold) {
  const test::OrientedPoints in = test::cubeFacePoints(10);
  const PrimitiveLibrary library = test::cubePlanes();
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  // Seeded with the answer (built from equal but separate leaves), the search
  // keeps it and stalls.
  std::vector<CsgTree> faces;
  for (std::size_t i = 0; i < 6; ++i) faces.push_back(CsgTree::leaf(library.primitive(i)));
  const CsgTree seed = CsgTree::intersect(faces);
  EvolveOptions options;
  options.stallGenerations = 5;
  const EvolveResult r = evolve(model, std::vector<CsgTree>{seed}, options);
  EXPECT_EQ(r.stop, EvolveStop::Stalled);
  EXPECT_EQ(r.generations, 5u);
  EXPECT_TRUE(isTheCube(r.best));
  EXPECT_LE(r.best.nodeCount(), 7u);
  // The callback can stop the search; a generation limit stops it.
  std::size_t calls = 0;
  options.stallGenerations = 0;
  const EvolveResult cancelled = evolve(model, {}, options, [&](const GenerationReport& g) {
    return ++calls < 3 && g.generation < 3;
  });
  EXPECT_EQ(cancelled.stop, EvolveStop::Cancelled);
  EXPECT_EQ(cancelled.generations, 3u);
  options.maxGenerations = 4;
  EXPECT_EQ(evolve(model, {}, options).stop, EvolveStop::Generations);
  // A foreign seed is refused.
  EXPECT_THROW(evolve(model, std::vector<CsgTree>{CsgTree::leaf(Sphere{})}, options),
               std::invalid_argument);
}

TEST(GeneticSearch, RoughPointsThenAllPoints) {
  const test::OrientedPoints in = test::cubeFacePoints(20);
  const PrimitiveLibrary library = test::cubePlanes();
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  const std::vector<std::uint32_t> subset = spreadSample(in.points.size(), 300, 1);
  test::OrientedPoints few;
  for (const std::uint32_t i : subset) {
    few.points.push_back(in.points[i]);
    few.normals.push_back(in.normals[i]);
  }
  const FitnessModel rough(few.points, few.normals, kDiagonal, library);
  EvolveOptions options;
  options.stallGenerations = 30;
  bool sawRough = false, sawFull = false;
  const EvolveResult r = evolve(
      model, {}, options,
      [&](const GenerationReport& g) {
        (g.rough ? sawRough : sawFull) = true;
        return true;
      },
      &rough);
  EXPECT_TRUE(sawRough);
  EXPECT_TRUE(sawFull);
  // The reported fitness is on all points.
  EXPECT_EQ(r.fitness.total, model.evaluate(r.best).total);
}

TEST(Variation, OffspringRespectTheDepthBoundAndUseLibraryLeaves) {
  const PrimitiveLibrary library = test::cubePlanes({Sphere{}});
  EvolveRng rng(3);
  VariationOptions options;
  options.maxDepth = 6;
  std::vector<CsgTree> trees;
  for (int i = 0; i < 50; ++i) trees.push_back(randomTree(rng, library, 5, 0.7));
  for (int round = 0; round < 20; ++round) {
    for (std::size_t i = 0; i + 1 < trees.size(); i += 2) {
      auto [a, b] = crossover(rng, trees[i], trees[i + 1], options);
      trees[i] = mutate(rng, a, library, options);
      trees[i + 1] = b;
    }
    for (const CsgTree& t : trees) {
      ASSERT_LE(t.depth(), 6u);
      ASSERT_TRUE(leavesAreTheLibrarys(t, library));
      ASSERT_NO_THROW(t.validate());
    }
  }
}

TEST(Redundancy, RemovesWhatDoesNotChangeTheFitness) {
  const test::OrientedPoints in = test::cubeFacePoints(10);
  // extra6: a half-space holding the whole cube; extra7: a sphere far away.
  const PrimitiveLibrary library =
      test::cubePlanes({HalfSpace{Vec3::UnitX(), 5.0}, Sphere{Vec3(9, 9, 9), 1.0}});
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  const CsgTree cube = test::cubeTree(library);
  const CsgTree x = library.leafTree(0);
  EXPECT_TRUE(normalizeTree(CsgTree::complement(CsgTree::complement(x))).structurallyEqual(x));
  const CsgTree padded =
      CsgTree::unite({CsgTree::intersect({cube, library.leafTree(6)}), library.leafTree(7)});
  const CsgTree cleaned = removeRedundancy(padded, model);
  EXPECT_TRUE(cleaned.structurallyEqual(cube)) << cleaned.nodeCount();
  EXPECT_GE(model.evaluate(cleaned).total, model.evaluate(padded).total);
  // A tree with nothing redundant is left alone.
  EXPECT_TRUE(removeRedundancy(cube, model).structurallyEqual(cube));
}

// Operands that cancel or repeat go, and with them the surfaces that bound
// no volume: the zero set of X − X is X's surface, which a fitness at the
// points would reward.
TEST(Redundancy, NormalizingDropsCancellingAndRepeatedOperands) {
  const CsgTree a = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2, 2, 2)}, "a");
  const CsgTree b = CsgTree::leaf(Box{Vec3(0, 0, 2), Mat3::Identity(), Vec3(1, 1, 1)}, "b");
  const CsgTree c = CsgTree::leaf(Sphere{Vec3(1, 1, 1), 0.5}, "c");
  const CsgTree bCopy = CsgTree::leaf(Box{Vec3(0, 0, 2), Mat3::Identity(), Vec3(1, 1, 1)});
  EXPECT_TRUE(
      normalizeTree(CsgTree::subtract({a, CsgTree::subtract({b, bCopy})})).structurallyEqual(a));
  EXPECT_TRUE(normalizeTree(CsgTree::unite({a, CsgTree::subtract({b, b})})).structurallyEqual(a));
  EXPECT_TRUE(normalizeTree(CsgTree::unite({a, CsgTree::intersect({b, CsgTree::complement(b)})}))
                  .structurallyEqual(a));
  EXPECT_TRUE(
      normalizeTree(CsgTree::unite({a, b, bCopy})).structurallyEqual(CsgTree::unite({a, b})));
  EXPECT_TRUE(normalizeTree(CsgTree::intersect({a, a})).structurallyEqual(a));
  EXPECT_TRUE(normalizeTree(CsgTree::subtract({a, b, c, bCopy}))
                  .structurallyEqual(CsgTree::subtract({a, b, c})));
  // An empty operand empties an intersection and a difference it is cut from.
  EXPECT_TRUE(normalizeTree(CsgTree::unite({c, CsgTree::intersect({a, CsgTree::subtract({b, b})})}))
                  .structurallyEqual(c));
  EXPECT_TRUE(normalizeTree(CsgTree::unite({c, CsgTree::subtract({CsgTree::subtract({a, a}), b})}))
                  .structurallyEqual(c));
  // Different operands are kept, in order; a tree empty as a whole is left.
  const CsgTree kept = CsgTree::subtract({a, b, c});
  EXPECT_TRUE(normalizeTree(kept).structurallyEqual(kept));
  const CsgTree empty = CsgTree::subtract({a, a});
  EXPECT_TRUE(normalizeTree(empty).structurallyEqual(empty));
}

// What removeRedundancy drops first: the subtrees whose solid is empty.
// An empty subtree changes no point of the solid, but a half-space in it
// must be written as a finite cube that covers it (tree.scad, tree.step),
// and its field can stand at zero on scan points.
TEST(Redundancy, EmptySubtreesAreThoseProvablyEmpty) {
  const CsgTree block = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2, 2, 1)}, "block");
  const CsgTree shaft = CsgTree::leaf(Cylinder{Vec3(5, 0, 0), Vec3::UnitX(), 1, 4}, "shaft");
  const CsgTree ball = CsgTree::leaf(Sphere{Vec3(0, 0, 3), 1}, "ball");
  const CsgTree ring = CsgTree::leaf(Torus{Vec3(0, 5, 0), Vec3(1, 1, 0).normalized(), 2, 0.5});
  const CsgTree cone = CsgTree::leaf(Cone{Vec3(0, -5, 0), Vec3::UnitZ(), 1, 0.5, 2}, "cone");
  const auto below = [](double z) { return CsgTree::leaf(HalfSpace{Vec3::UnitZ(), z}); };
  // Inside the subtracted half-space (a cap on its plane too), beyond an
  // intersected one, or outside a complemented one: empty.
  int k = 0;
  for (const CsgTree& empty :
       {CsgTree::subtract({shaft, below(1.0)}), CsgTree::subtract({ring, below(2.5)}),
        CsgTree::subtract({cone, below(1.0)}), CsgTree::intersect({below(1.9), ball}),
        CsgTree::intersect({ball, CsgTree::complement(below(4.0))}),
        CsgTree::subtract({ball, CsgTree::complement(below(1.0))}),
        CsgTree::intersect({block, shaft}),  // bounds apart
        CsgTree::subtract({CsgTree::unite({shaft, ball}), below(5.0)})}) {
    SCOPED_TRACE(k++);
    EXPECT_TRUE(withoutEmptySubtrees(CsgTree::unite({block, empty})).structurallyEqual(block));
    EXPECT_TRUE(withoutEmptySubtrees(CsgTree::subtract({block, empty, ball}))
                    .structurallyEqual(CsgTree::subtract({block, ball})));
  }
  // Crossing the plane, or not provably apart: kept, the tree untouched.
  k = 0;
  for (const CsgTree& kept :
       {CsgTree::subtract({shaft, below(0.5)}), CsgTree::subtract({ring, below(1.0)}),
        CsgTree::intersect({below(2.1), ball}),
        CsgTree::intersect({block, CsgTree::leaf(Sphere{Vec3(0, 0, 1.5), 1})}),
        CsgTree::subtract({cone, below(0.5)})}) {
    SCOPED_TRACE(k++);
    const CsgTree t = CsgTree::unite({block, kept});
    EXPECT_EQ(withoutEmptySubtrees(t).root(), t.root());
  }
  // An empty tree as a whole is left as it was.
  const CsgTree all = CsgTree::subtract({shaft, below(1.0)});
  EXPECT_EQ(withoutEmptySubtrees(all).root(), all.root());
}

// InverseCSG 159's scanner scan gave a union member that only grazed the
// block: a corner hole's cylinder (r 0.75 at (2.48, 2.48)) intersected with
// a box whose corner (1.94, 3.0) lies 0.745 from its axis, a sliver of about
// 1e-4 in volume. Members and cuts changing less than the volume given go;
// a plate thinner than the lattice's spacing, a small hole and a shallow
// pocket do not.
TEST(Redundancy, OperandsThatChangeLessThanTheVolumeGiven) {
  const CsgTree block = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(3, 3, 5)}, "block");
  const CsgTree corner = CsgTree::leaf(Cylinder{Vec3(2.48, 2.48, 0), Vec3::UnitZ(), 0.75, 10});
  const CsgTree beside = CsgTree::leaf(Box{Vec3(0, 8, 0), Mat3::Identity(), Vec3(1.94, 5, 5)});
  const CsgTree hole = CsgTree::leaf(Cylinder{Vec3(-1, -1, 0), Vec3::UnitZ(), 0.3, 10}, "hole");
  const double h = 0.17;  // a voxel
  const CsgTree grazing =
      CsgTree::unite({CsgTree::subtract({block, hole}), CsgTree::intersect({corner, beside})});
  const CsgTree pruned = withoutNegligibleOperands(grazing, 0.5 * h, h * h * h);
  EXPECT_TRUE(pruned.structurallyEqual(CsgTree::subtract({block, hole})))
      << pruned.primitiveCount();
  // A cut that grazes the block's side (0.001 deep: 5e-4 in volume).
  const CsgTree nick = CsgTree::leaf(Cylinder{Vec3(3.749, 0, 0), Vec3::UnitZ(), 0.75, 10});
  EXPECT_TRUE(withoutNegligibleOperands(CsgTree::subtract({block, hole, nick}), 0.5 * h, h * h * h)
                  .structurallyEqual(CsgTree::subtract({block, hole})));
  // Kept: a plate on the block's side a fifth of the lattice's spacing thick
  // and parallel to the axes (2 x 1 in area: 0.034, 7 voxels' volume), the
  // small hole, a pocket 0.1 deep (a cut of 0.4).
  const CsgTree thin = CsgTree::leaf(Box{Vec3(0, 3.5, 0), Mat3::Identity(), Vec3(1, 0.5, 0.0085)});
  const CsgTree pocket = CsgTree::leaf(Box{Vec3(0, 0, 4.95), Mat3::Identity(), Vec3(1, 1, 0.05)});
  const CsgTree kept = CsgTree::subtract({CsgTree::unite({block, thin}), hole, pocket});
  EXPECT_EQ(withoutNegligibleOperands(kept, 0.5 * h, h * h * h).root(), kept.root());
  // A half-space that cuts nothing of a cube goes; the cube, whose box (the
  // half-space's bounds) is unbounded, stays.
  const CsgTree cube = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(1, 1, 1)}, "cube");
  const CsgTree below = CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 1.5});
  EXPECT_TRUE(withoutNegligibleOperands(CsgTree::intersect({cube, below}), 0.5 * h, h * h * h)
                  .structurallyEqual(cube));
  // Nor does a lattice too coarse to resolve the volume drop anything: the
  // same intersection with a block 60 x 60 x 100 (2^18 points over its box
  // stand more than a voxel's volume each).
  const CsgTree slab = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(30, 30, 50)});
  const CsgTree far = CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 60.0});
  const CsgTree clipped = CsgTree::intersect({slab, far});
  EXPECT_EQ(withoutNegligibleOperands(clipped, 0.5 * h, h * h * h).root(), clipped.root());
}

// Points of a lattice of `step` over `box` where the two trees' solids differ.
std::size_t solidsDiffer(const CsgTree& a, const CsgTree& b, const Aabb& box, double step) {
  std::vector<Vec3> points;
  for (double x = box.min.x(); x <= box.max.x(); x += step)
    for (double y = box.min.y(); y <= box.max.y(); y += step)
      for (double z = box.min.z(); z <= box.max.z(); z += step) points.emplace_back(x, y, z);
  std::vector<double> va(points.size()), vb(points.size());
  a.values(points, va);
  b.values(points, vb);
  std::size_t n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) n += (va[i] >= 0.0) != (vb[i] >= 0.0);
  return n;
}

// bearing_housing's scanner scan gave its bore twice: cut from the flange to
// the top, and again from the hub to z = 8, one cylinder of one radius on
// one axis. A flange and the hub standing on it, each with its part of a
// bore: one bore, cut from both; a cross pin through the bore keeps its
// middle (the bore cuts the two members only); a union that is itself cut
// takes the bore among its cutters. Not merged: a bore of another radius,
// a bore off the axis.
TEST(Redundancy, ACutOfOneSurfaceInTwoMembersIsMadeOnce) {
  const auto cylinder = [](double z0, double z1, double r, double x = 0.0) {
    return CsgTree::leaf(Cylinder{Vec3(x, 0, 0.5 * (z0 + z1)), Vec3::UnitZ(), r, z1 - z0}, "c");
  };
  const CsgTree flange = cylinder(0, 2, 4), hub = cylinder(2, 6, 2);
  const CsgTree low = cylinder(-0.1, 2.1, 1), high = cylinder(1.9, 6.1, 1);
  const double h = 0.1;  // a voxel
  const Aabb box{Vec3(-4.5, -4.5, -0.5), Vec3(4.5, 4.5, 6.5)};
  const CsgTree twice =
      CsgTree::unite({CsgTree::subtract({flange, low}), CsgTree::subtract({hub, high})});
  const CsgTree once = withSharedCuts(twice, 0.5 * h, h * h * h);
  const CsgTree bore = cylinder(-0.1, 6.1, 1);
  EXPECT_TRUE(
      once.structurallyEqual(CsgTree::subtract({CsgTree::unite({flange, hub}), bore}), 1e-12))
      << once.primitiveCount();
  EXPECT_EQ(solidsDiffer(twice, once, box, 0.1), 0u);
  // The pin across the bore stays whole.
  const CsgTree pin = CsgTree::leaf(Box{Vec3(0, 0, 5), Mat3::Identity(), Vec3(3, 0.3, 0.3)});
  const CsgTree pinned =
      CsgTree::unite({CsgTree::subtract({flange, low}), CsgTree::subtract({hub, high}), pin});
  const CsgTree sharedPinned = withSharedCuts(pinned, 0.5 * h, h * h * h);
  EXPECT_TRUE(sharedPinned.structurallyEqual(
      CsgTree::unite({pin, CsgTree::subtract({CsgTree::unite({flange, hub}), bore})}), 1e-12))
      << sharedPinned.primitiveCount();
  EXPECT_EQ(solidsDiffer(pinned, sharedPinned, box, 0.1), 0u);
  // A cut union: the bore joins its cutters.
  const CsgTree ball = CsgTree::leaf(Sphere{Vec3(0, 0, 7), 1.5});
  const CsgTree cut = withSharedCuts(CsgTree::subtract({twice, ball}), 0.5 * h, h * h * h);
  EXPECT_TRUE(
      cut.structurallyEqual(CsgTree::subtract({CsgTree::unite({flange, hub}), bore, ball}), 1e-12))
      << cut.primitiveCount();
  // Slots of one width and length through a plate and the block on it: one slot.
  const auto box3 = [](Vec3 lo, Vec3 hi) {
    return CsgTree::leaf(Box{0.5 * (lo + hi), Mat3::Identity(), 0.5 * (hi - lo)});
  };
  const CsgTree slots =
      CsgTree::unite({CsgTree::subtract({box3(Vec3(-4, -4, 0), Vec3(4, 4, 1)),
                                         box3(Vec3(-1, -3, -0.1), Vec3(1, 3, 1.1))}),
                      CsgTree::subtract({box3(Vec3(-2, -4, 1), Vec3(2, 4, 3)),
                                         box3(Vec3(-1, -3, 0.9), Vec3(1, 3, 3.1))})});
  const CsgTree slot = withSharedCuts(slots, 0.5 * h, h * h * h);
  EXPECT_EQ(slot.primitiveCount(), 3u);
  EXPECT_EQ(solidsDiffer(slots, slot, box, 0.1), 0u);
  // Two lengths of one bore cut from one block, two halves of one shaft
  // joined: one cylinder each.
  const CsgTree block = box3(Vec3(-3, -3, 0), Vec3(3, 3, 6));
  const CsgTree halves = CsgTree::subtract({block, low, high});
  EXPECT_TRUE(withSharedCuts(halves, 0.5 * h, h * h * h)
                  .structurallyEqual(CsgTree::subtract({block, bore}), 1e-12));
  const CsgTree shaft = CsgTree::unite({low, high});
  EXPECT_TRUE(withSharedCuts(shaft, 0.5 * h, h * h * h).structurallyEqual(bore, 1e-12));
  // Another radius, another axis: kept as they were.
  for (const CsgTree& other : {cylinder(1.9, 6.1, 1.2), cylinder(1.9, 6.1, 1, 0.5)}) {
    const CsgTree t =
        CsgTree::unite({CsgTree::subtract({flange, low}), CsgTree::subtract({hub, other})});
    EXPECT_EQ(withSharedCuts(t, 0.5 * h, h * h * h).root(), t.root());
  }
}

// The tree of a scanned plate of bosses (data/regressions): its subtree
// difference(cylinder9, halfspace5) is empty, the cylinder (radius 214.8,
// reaching x = 489 beside a part 150 wide) lying under the plane. It goes,
// alone, and the solid stays the same.
TEST(Redundancy, ThePlateOfBossesLosesItsEmptySubtree) {
  const CsgTree tree =
      readTreeJson(test::dataDir() / "regressions" / "halfspace-export-plate-of-bosses.json");
  const CsgTree pruned = withoutEmptySubtrees(tree);
  EXPECT_EQ(pruned.primitiveCount() + 2, tree.primitiveCount());
  EXPECT_EQ(withoutEmptySubtrees(pruned).root(), pruned.root());
  const Aabb box = tree.bounds();
  test::Rng rng(3);
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p = test::randomPoint(rng, box);
    ASSERT_EQ(tree.contains(p), pruned.contains(p)) << test::str(p);
  }
}

}  // namespace
}  // namespace csgvox
