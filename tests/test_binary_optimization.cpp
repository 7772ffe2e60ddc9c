// Phase 1 (Eq. 4) and phase 2 (Eq. 6) solvers against brute-force
// enumeration on random instances.

#include <gtest/gtest.h>

#include <bit>
#include <random>

#include "optimize/subtree_selection.h"
#include "optimize/union_selection.h"
#include "random_voxel_sets.h"

namespace csgvox {
namespace {

using test::randomSet;

double bruteForceSubtree(const VoxelSet& root, const VoxelSet& inside,
                         const std::vector<const VoxelSet*>& nb, double alpha) {
  const std::size_t L = 2 * nb.size();
  double best = 1e300;
  for (std::uint64_t mask = 0; mask < (std::uint64_t(1) << L); ++mask) {
    std::vector<std::uint8_t> x(L);
    for (std::size_t a = 0; a < L; ++a) x[a] = (mask >> a) & 1;
    best = std::min(best, subtreeEnergy(root, inside, nb, x, alpha));
  }
  return best;
}

TEST(SubtreeSelection, MatchesBruteForceOnRandomInstances) {
  std::mt19937_64 rng(7);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t bits = 300 + trial * 7;
    const VoxelSet inside = randomSet(bits, rng, 4, bits / 3);
    const VoxelSet root = randomSet(bits, rng, 2, bits / 2);
    const int n = 1 + trial % 7;  // up to 14 actions: 16384 subsets
    std::vector<VoxelSet> sets;
    for (int i = 0; i < n; ++i) sets.push_back(randomSet(bits, rng, 2, bits / 4));
    std::vector<const VoxelSet*> nb;
    std::vector<std::uint32_t> ids;
    for (int i = 0; i < n; ++i) nb.push_back(&sets[i]), ids.push_back(std::uint32_t(100 + i));
    for (double alpha : {0.9, 0.3}) {
      SubtreeOptions o;
      o.alpha = alpha;
      o.minFeatureVoxels = 0.0;  // Wu's 1/L, as subtreeEnergy computes it
      const SubtreeResult r = selectSubtree(root, inside, nb, ids, o);
      const double brute = bruteForceSubtree(root, inside, nb, alpha);
      EXPECT_TRUE(r.provedOptimal);
      EXPECT_NEAR(r.energy, brute, 1e-12) << "trial " << trial;
      // The reported energy and voxels are those of the reported actions.
      std::vector<std::uint8_t> x(2 * n, 0);
      VoxelSet sub = root;
      for (const SubtreeAction& a : r.actions) {
        ASSERT_GE(a.primitive, 100u);
        const std::size_t i = a.primitive - 100;
        x[2 * i + (a.subtract ? 1 : 0)] = 1;
        if (a.subtract) {
          sub.subtract(sets[i]);
        } else {
          sub &= sets[i];
        }
      }
      EXPECT_NEAR(subtreeEnergy(root, inside, nb, x, alpha), r.energy, 1e-12);
      EXPECT_EQ(sub, r.voxels);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 120);
}

// The production cost (minFeatureVoxels > 0): an action costs
// minFeatureVoxels / |V+(root)|, and actions that can never pay for
// themselves are dropped before the search. Still the exact optimum.
TEST(SubtreeSelection, MatchesBruteForceWithTheMinFeatureCost) {
  std::mt19937_64 rng(13);
  int truncated = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t bits = 250 + std::size_t(trial) * 5;
    const VoxelSet inside = randomSet(bits, rng, 4, bits / 3);
    const VoxelSet root = randomSet(bits, rng, 2, bits / 2);
    const int n = 1 + trial % 7;
    std::vector<VoxelSet> sets;
    for (int i = 0; i < n; ++i) sets.push_back(randomSet(bits, rng, 2, bits / 4));
    std::vector<const VoxelSet*> nb;
    std::vector<std::uint32_t> ids;
    for (int i = 0; i < n; ++i)
      nb.push_back(&sets[std::size_t(i)]), ids.push_back(std::uint32_t(i));
    SubtreeOptions o;
    o.minFeatureVoxels = 6.0;
    const SubtreeResult r = selectSubtree(root, inside, nb, ids, o);
    const double plusRoot = double(VoxelSet::countAnd(root, inside));
    const double invL = o.minFeatureVoxels / std::max(1.0, plusRoot);
    double best = 1e300;
    for (std::uint32_t mask = 0; mask < (1u << (2 * n)); ++mask) {
      VoxelSet sub = root;
      for (int i = 0; i < n; ++i) {
        if (mask >> (2 * i) & 1) sub &= sets[std::size_t(i)];
        if (mask >> (2 * i + 1) & 1) sub.subtract(sets[std::size_t(i)]);
      }
      const double num = double(VoxelSet::countAnd(sub, inside));
      const double den = plusRoot + double(VoxelSet::countAndNot(sub, inside));
      best = std::min(best, std::popcount(mask) * invL - o.alpha * (den > 0 ? num / den : 0.0));
    }
    EXPECT_TRUE(r.provedOptimal);
    EXPECT_NEAR(r.energy, best, 1e-12) << "trial " << trial;
    truncated += r.actions.empty() ? 0 : 1;
  }
  EXPECT_GE(truncated, 10);  // the instances are not all left alone
}

TEST(SubtreeSelection, TruncatesABoxToTheInsideExactly) {
  // Root covers [0, 100); inside is [0, 60); neighbour A = [0, 60) (intersect
  // with it), B = [60, 100) (subtract it), C unrelated.
  VoxelSet root(100), inside(100), a(100), b(100), c(100);
  for (int i = 0; i < 100; ++i) root.set(i);
  for (int i = 0; i < 60; ++i) inside.set(i), a.set(i);
  for (int i = 60; i < 100; ++i) b.set(i);
  for (int i = 10; i < 20; ++i) c.set(i);
  SubtreeOptions o;
  o.minFeatureVoxels = 0.0;
  const SubtreeResult r = selectSubtree(root, inside, {&a, &b, &c}, {0, 1, 2}, o);
  ASSERT_EQ(r.actions.size(), 1u);  // one action suffices; two would cost more
  EXPECT_EQ(r.voxels, inside);
  EXPECT_TRUE(r.provedOptimal);
}

double bruteForceUnion(const VoxelSet& inside, const std::vector<const VoxelSet*>& cands,
                       double beta) {
  double best = 1e300;
  for (std::uint64_t mask = 0; mask < (std::uint64_t(1) << cands.size()); ++mask) {
    std::vector<std::uint8_t> z(cands.size());
    for (std::size_t i = 0; i < cands.size(); ++i) z[i] = (mask >> i) & 1;
    best = std::min(best, unionEnergy(inside, cands, z, beta));
  }
  return best;
}

TEST(UnionSelection, MatchesBruteForceOnRandomInstances) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t bits = 500 + trial * 5;
    const VoxelSet inside = randomSet(bits, rng, 5, bits / 4);
    const int m = 2 + trial % 15;  // up to 16 candidates
    std::vector<VoxelSet> sets;
    for (int i = 0; i < m; ++i) sets.push_back(randomSet(bits, rng, 1, bits / 5) & inside);
    std::vector<const VoxelSet*> cands;
    for (const VoxelSet& s : sets) cands.push_back(&s);
    for (double beta : {0.9, 0.2}) {
      UnionOptions o;
      o.beta = beta;
      o.minFeatureVoxels = 0.0;  // Wu's 1/M, as unionEnergy computes it
      const UnionResult r = selectUnion(inside, cands, o);
      EXPECT_TRUE(r.provedOptimal);
      EXPECT_NEAR(r.energy, bruteForceUnion(inside, cands, beta), 1e-12) << "trial " << trial;
      std::vector<std::uint8_t> z(m, 0);
      for (std::uint32_t i : r.chosen) z[i] = 1;
      EXPECT_NEAR(unionEnergy(inside, cands, z, beta), r.energy, 1e-12);
    }
  }
}

TEST(UnionSelection, MatchesBruteForceWithTheMinFeatureCost) {
  std::mt19937_64 rng(19);
  int several = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t bits = 400 + std::size_t(trial) * 5;
    const VoxelSet inside = randomSet(bits, rng, 5, bits / 4);
    const int m = 2 + trial % 13;
    std::vector<VoxelSet> sets;
    for (int i = 0; i < m; ++i) sets.push_back(randomSet(bits, rng, 1, bits / 5) & inside);
    std::vector<const VoxelSet*> cands;
    for (const VoxelSet& s : sets) cands.push_back(&s);
    UnionOptions o;
    o.minFeatureVoxels = 20.0;
    const UnionResult r = selectUnion(inside, cands, o);
    const double total = double(inside.count());
    double best = 1e300;
    for (std::uint32_t mask = 0; mask < (1u << m); ++mask) {
      VoxelSet u(bits);
      for (int i = 0; i < m; ++i) {
        if (mask >> i & 1) u |= sets[std::size_t(i)];
      }
      best = std::min(best, (std::popcount(mask) * o.minFeatureVoxels -
                             o.beta * double(VoxelSet::countAnd(u, inside))) /
                                total);
    }
    EXPECT_TRUE(r.provedOptimal);
    EXPECT_NEAR(r.energy, best, 1e-12) << "trial " << trial;
    several += r.chosen.size() > 1 ? 1 : 0;
  }
  EXPECT_GE(several, 10);  // the optimum is not a single candidate throughout
}

TEST(UnionSelection, ScalesToHundredsOfCandidates) {
  std::mt19937_64 rng(5);
  const std::size_t bits = 64 * 64 * 64;
  const VoxelSet inside = randomSet(bits, rng, 40, bits / 20);
  std::vector<VoxelSet> sets;
  for (int i = 0; i < 300; ++i) sets.push_back(randomSet(bits, rng, 1, bits / 30) & inside);
  std::vector<const VoxelSet*> cands;
  for (const VoxelSet& s : sets) cands.push_back(&s);
  UnionOptions o;
  o.minFeatureVoxels = 0.0;
  o.nodeBudget = 20000;
  const UnionResult r = selectUnion(inside, cands, o);
  // Not necessarily proved optimal, but never worse than taking nothing or
  // taking the single best candidate, and the reported energy is the choice's.
  std::vector<std::uint8_t> z(cands.size(), 0);
  EXPECT_LE(r.energy, unionEnergy(inside, cands, z, o.beta));
  for (std::size_t i = 0; i < cands.size(); ++i) {
    z[i] = 1;
    EXPECT_LE(r.energy, unionEnergy(inside, cands, z, o.beta) + 1e-12) << i;
    z[i] = 0;
  }
  for (std::uint32_t i : r.chosen) z[i] = 1;
  EXPECT_NEAR(unionEnergy(inside, cands, z, o.beta), r.energy, 1e-12);
  EXPECT_GT(r.covered, 0u);
  EXPECT_FALSE(r.chosen.empty());
}

}  // namespace
}  // namespace csgvox
