// Friedrich's search-space partitioning (evolve/partition.h) and the
// partitioned search (evolve/partitioned_search.h).

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "evolve/partitioned_search.h"
#include "evolve_fixtures.h"

namespace csgvox {
namespace {

Aabb box(Vec3 lo, Vec3 hi) {
  Aabb b;
  b.extend(lo);
  b.extend(hi);
  return b;
}

TEST(Partition, OverlapGraphJoinsIntersectingBoxesOnly) {
  const std::vector<Aabb> hulls = {box({0, 0, 0}, {1, 1, 1}), box({1, 0, 0}, {2, 1, 1}),
                                   box({3, 0, 0}, {4, 1, 1}), Aabb{},
                                   box({0.5, 0.5, 0.5}, {3.5, 0.6, 0.6})};
  const Graph g = overlapGraph(hulls);
  EXPECT_EQ(g[0], (std::vector<std::size_t>{1, 4}));  // touching counts
  EXPECT_EQ(g[1], (std::vector<std::size_t>{0, 4}));
  EXPECT_EQ(g[2], (std::vector<std::size_t>{4}));
  EXPECT_TRUE(g[3].empty());  // an empty hull overlaps nothing
  EXPECT_EQ(g[4], (std::vector<std::size_t>{0, 1, 2}));
}

// Every maximal clique by enumerating all vertex subsets.
std::vector<std::vector<std::size_t>> bruteForceCliques(const Graph& g) {
  const std::size_t n = g.size();
  auto adjacent = [&](std::size_t a, std::size_t b) {
    return std::binary_search(g[a].begin(), g[a].end(), b);
  };
  auto isClique = [&](unsigned mask) {
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a + 1; b < n; ++b)
        if ((mask >> a & 1) && (mask >> b & 1) && !adjacent(a, b)) return false;
    return true;
  };
  std::vector<std::vector<std::size_t>> out;
  for (unsigned mask = 1; mask < (1u << n); ++mask) {
    if (!isClique(mask)) continue;
    bool maximal = true;
    for (std::size_t v = 0; v < n && maximal; ++v)
      if (!(mask >> v & 1) && isClique(mask | (1u << v))) maximal = false;
    if (!maximal) continue;
    std::vector<std::size_t> c;
    for (std::size_t v = 0; v < n; ++v)
      if (mask >> v & 1) c.push_back(v);
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Partition, MaximalCliquesMatchEnumerationOnRandomGraphs) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t n = 1 + trial % 11;
    const double density = 0.15 + 0.8 * (trial % 5) / 4.0;
    Graph g(n);
    std::bernoulli_distribution edge(density);
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a + 1; b < n; ++b)
        if (edge(rng)) g[a].push_back(b), g[b].push_back(a);
    for (auto& adj : g) std::sort(adj.begin(), adj.end());
    EXPECT_EQ(maximalCliques(g), bruteForceCliques(g)) << "trial " << trial;
  }
}

// Oriented points on a sphere (Fibonacci spiral).
void spherePoints(const Vec3& c, double r, int n, test::OrientedPoints& out) {
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (i + 0.5) * 2.0 / n;
    const double t = i * 2.399963229728653, s = std::sqrt(1.0 - z * z);
    const Vec3 normal(s * std::cos(t), s * std::sin(t), z);
    out.points.push_back(c + r * normal);
    out.normals.push_back(normal);
  }
}

PrimitiveLibrary spheres(std::vector<Sphere> list) {
  std::vector<Primitive> primitives;
  std::vector<std::string> names;
  for (const Sphere& s : list) {
    primitives.push_back(s);
    names.push_back("sphere" + std::to_string(names.size()));
  }
  return PrimitiveLibrary(std::move(primitives), std::move(names));
}

TEST(Partition, CliquesOfOverlappingSupportsWithTheirPoints) {
  // Spheres 0 and 1 overlap, 2 is apart, 3 has no point near it.
  test::OrientedPoints in;
  spherePoints({0, 0, 0}, 1.0, 300, in);
  spherePoints({1.5, 0, 0}, 1.0, 200, in);
  spherePoints({6, 0, 0}, 1.0, 100, in);
  const PrimitiveLibrary library = spheres({Sphere{{0, 0, 0}, 1.0}, Sphere{{1.5, 0, 0}, 1.0},
                                            Sphere{{6, 0, 0}, 1.0}, Sphere{{0, 6, 0}, 0.5}});
  const PrimitiveSupport support = primitiveSupport(in.points, library, 1e-6);
  EXPECT_TRUE(support.hulls[3].isEmpty());
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    const std::uint32_t expected = i < 300 ? 0 : i < 500 ? 1 : 2;
    ASSERT_EQ(support.nearest[i], expected) << "point " << i;
  }
  const std::vector<SearchPartition> parts = partitionSearch(support, 0.01);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].primitives, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(parts[0].points.size(), 500u);
  EXPECT_EQ(parts[1].primitives, (std::vector<std::size_t>{2}));
  EXPECT_EQ(parts[1].points.size(), 100u);
  EXPECT_EQ(parts[1].points.front(), 500u);
}

TEST(Partition, MergeJoinsAtTheLargestCommonSubtreeUnderUnions) {
  const PrimitiveLibrary lib =
      spheres({Sphere{{0, 0, 0}, 1}, Sphere{{1, 0, 0}, 1}, Sphere{{2, 0, 0}, 1},
               Sphere{{3, 0, 0}, 1}, Sphere{{4, 0, 0}, 1}});
  const CsgTree a = lib.leafTree(0), b = lib.leafTree(1), c = lib.leafTree(2), d = lib.leafTree(3),
                e = lib.leafTree(4);
  const CsgTree bc = CsgTree::subtract({b, c});
  // t0 = a ∪ (b − c), t1 = (b − c) ∪ d: same size, so t0's node is replaced.
  const CsgTree merged = mergePartitionTrees({CsgTree::unite({a, bc}), CsgTree::unite({bc, d})});
  EXPECT_TRUE(merged.structurallyEqual(CsgTree::unite({a, CsgTree::unite({bc, d})})));
  // The common subtree of the larger tree is replaced by the smaller tree.
  const CsgTree large = CsgTree::unite({CsgTree::intersect({a, e}), bc});
  const CsgTree joined = mergePartitionTrees({CsgTree::subtract({bc, d}), large});
  EXPECT_TRUE(joined.structurallyEqual(
      CsgTree::unite({CsgTree::intersect({a, e}), CsgTree::subtract({bc, d})})));
}

TEST(Partition, MergeUnitesWhatHasNoValidMergeNode) {
  const PrimitiveLibrary lib =
      spheres({Sphere{{0, 0, 0}, 1}, Sphere{{1, 0, 0}, 1}, Sphere{{2, 0, 0}, 1}});
  const CsgTree a = lib.leafTree(0), b = lib.leafTree(1), c = lib.leafTree(2);
  // No common subtree.
  EXPECT_TRUE(mergePartitionTrees({a, b}).structurallyEqual(CsgTree::unite({a, b})));
  // The common leaf b sits under an intersection (not a valid merge node) in
  // both trees.
  const CsgTree t0 = CsgTree::intersect({a, b}), t1 = CsgTree::subtract({c, b});
  const CsgTree m = mergePartitionTrees({t0, t1});
  EXPECT_EQ(m.root()->kind, NodeKind::Union);
  EXPECT_EQ(m.primitiveCount(), 4u);
  // One tree is itself; none or an empty one is refused.
  EXPECT_TRUE(mergePartitionTrees({t0}).structurallyEqual(t0));
  EXPECT_THROW(mergePartitionTrees({}), std::invalid_argument);
  EXPECT_THROW(mergePartitionTrees({t0, CsgTree{}}), std::invalid_argument);
}

TEST(PartitionedSearch, TwoApartSpheresAreTwoPartitionsAndTheirUnion) {
  test::OrientedPoints in;
  spherePoints({-2, 0, 0}, 1.0, 400, in);
  spherePoints({2, 0, 0}, 0.7, 400, in);
  const PrimitiveLibrary library =
      spheres({Sphere{{-2, 0, 0}, 1.0}, Sphere{{2, 0, 0}, 0.7}, Sphere{{0, 3, 0}, 0.4}});
  EvolveOptions eo;
  eo.maxGenerations = 200;
  eo.stallGenerations = 40;
  const PartitionedResult r =
      evolvePartitioned(in.points, in.normals, 6.0, library, FitnessOptions{}, eo);
  ASSERT_EQ(r.partitions.size(), 2u);
  EXPECT_EQ(r.partitions[0].points, 400u);
  EXPECT_EQ(r.partitions[0].nodes, 1u);
  const CsgTree expected = CsgTree::unite({library.leafTree(0), library.leafTree(1)});
  EXPECT_EQ(r.mergedNodes, 3u);
  EXPECT_EQ(r.search.best.primitiveCount(), 2u);
  EXPECT_EQ(r.search.best.operationCount(), 1u);
  EXPECT_EQ(r.search.best.root()->kind, NodeKind::Union);
  EXPECT_TRUE(r.search.best.contains({-2, 0, 0}) && r.search.best.contains({2, 0, 0}));
  EXPECT_FALSE(r.search.best.contains({0, 3, 0}));
}

TEST(PartitionedSearch, CubeCornersMergeIntoTheExactCubeWhateverTheThreads) {
  const test::OrientedPoints in = test::cubeFacePoints(16);
  const PrimitiveLibrary library = test::cubePlanes();
  EvolveOptions eo;
  eo.seed = 3;
  eo.maxGenerations = 400;
  eo.stallGenerations = 60;
  PartitionedResult one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = evolvePartitioned(in.points, in.normals, 2 * std::sqrt(3.0), library, {}, eo);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = evolvePartitioned(in.points, in.normals, 2 * std::sqrt(3.0), library, {}, eo);
  }
  // A face meets four others at its edges, never the opposite face: the
  // maximal cliques are the eight corners.
  ASSERT_EQ(one.partitions.size(), 8u);
  for (const PartitionRun& p : one.partitions) EXPECT_EQ(p.primitives.size(), 3u);
  EXPECT_TRUE(one.search.best.structurallyEqual(two.search.best));
  EXPECT_EQ(one.search.fitness.total, two.search.fitness.total);
  const CsgTree& t = one.search.best;
  EXPECT_EQ(t.primitiveCount(), 6u);
  EXPECT_EQ(t.nodeCount(), 11u);
  for (const Vec3& p : {Vec3(0.9, 0.9, 0.9), Vec3(-0.9, 0.5, -0.9)}) EXPECT_TRUE(t.contains(p));
  for (const Vec3& p : {Vec3(1.1, 0, 0), Vec3(0, -1.1, 0), Vec3(0, 0, 1.1)})
    EXPECT_FALSE(t.contains(p));
}

}  // namespace
}  // namespace csgvox
