#include <gtest/gtest.h>

#include <random>
#include <set>

#include "core/cpu_features.h"
#include "voxel/voxel_set.h"

namespace csgvox {
namespace {

// A reference implementation on std::set for random comparisons.
std::set<std::size_t> members(const VoxelSet& s) {
  std::set<std::size_t> m;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s.test(i)) m.insert(i);
  }
  return m;
}

VoxelSet randomSet(std::size_t bits, double density, std::mt19937_64& rng) {
  VoxelSet s(bits);
  std::bernoulli_distribution b(density);
  for (std::size_t i = 0; i < bits; ++i) {
    if (b(rng)) s.set(i);
  }
  return s;
}

TEST(VoxelSet, SetTestResetCount) {
  VoxelSet s(130);
  EXPECT_EQ(s.size(), 130u);
  EXPECT_EQ(s.wordCount(), 3u);
  EXPECT_TRUE(s.none());
  s.set(0);
  s.set(64);
  s.set(129);
  EXPECT_EQ(s.count(), 3u);
  EXPECT_TRUE(s.test(129));
  EXPECT_FALSE(s.test(128));
  s.reset(64);
  EXPECT_EQ(s.count(), 2u);
  s.fill();
  EXPECT_EQ(s.count(), 130u);  // the padding bits of the last word stay clear
  EXPECT_EQ(s.complemented().count(), 0u);
  s.clear();
  EXPECT_TRUE(s.none());
}

TEST(VoxelSet, AlgebraMatchesAReferenceSet) {
  std::mt19937_64 rng(3);
  for (std::size_t bits : {1u, 63u, 64u, 65u, 1000u, 4096u + 17u}) {
    for (double density : {0.01, 0.5, 0.97}) {
      const VoxelSet a = randomSet(bits, density, rng), b = randomSet(bits, 0.5, rng);
      const auto ma = members(a), mb = members(b);
      std::set<std::size_t> i, u, d;
      std::set_intersection(ma.begin(), ma.end(), mb.begin(), mb.end(), std::inserter(i, i.end()));
      std::set_union(ma.begin(), ma.end(), mb.begin(), mb.end(), std::inserter(u, u.end()));
      std::set_difference(ma.begin(), ma.end(), mb.begin(), mb.end(), std::inserter(d, d.end()));
      EXPECT_EQ(members(a & b), i);
      EXPECT_EQ(members(a | b), u);
      EXPECT_EQ(members(a - b), d);
      EXPECT_EQ(VoxelSet::countAnd(a, b), i.size());
      EXPECT_EQ(VoxelSet::countOr(a, b), u.size());
      EXPECT_EQ(VoxelSet::countAndNot(a, b), d.size());
      EXPECT_EQ(VoxelSet::intersects(a, b), !i.empty());
      EXPECT_EQ(a.complemented().count(), bits - ma.size());
      EXPECT_EQ(a.count(), ma.size());
    }
  }
}

// Every operation of one pair of sets, as computed on one instruction-set level.
struct Results {
  std::size_t countAnd, countAndNot, countOr, countA;
  bool intersects;
  VoxelSet anded, ored, subtracted, selfAnded, selfOred, selfSubtracted;
  bool operator==(const Results&) const = default;
};

Results resultsOn(SimdLevel level, const VoxelSet& a, const VoxelSet& b) {
  const ScopedSimdLevel scoped(level);
  EXPECT_EQ(simdLevel(), level);
  VoxelSet anded = a, ored = a, subtracted = a, selfAnded = a, selfOred = a, selfSubtracted = a;
  anded &= b;
  ored |= b;
  subtracted.subtract(b);
  selfAnded &= selfAnded;
  selfOred |= selfOred;
  selfSubtracted.subtract(selfSubtracted);
  return {VoxelSet::countAnd(a, b),
          VoxelSet::countAndNot(a, b),
          VoxelSet::countOr(a, b),
          a.count(),
          VoxelSet::intersects(a, b),
          anded,
          ored,
          subtracted,
          selfAnded,
          selfOred,
          selfSubtracted};
}

// The counts by bit tests alone, independent of every kernel.
void expectMatchesBitTests(const Results& r, const VoxelSet& a, const VoxelSet& b) {
  std::size_t both = 0, onlyA = 0, either = 0, inA = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    both += a.test(i) && b.test(i);
    onlyA += a.test(i) && !b.test(i);
    either += a.test(i) || b.test(i);
    inA += a.test(i);
  }
  EXPECT_EQ(r.countAnd, both);
  EXPECT_EQ(r.countAndNot, onlyA);
  EXPECT_EQ(r.countOr, either);
  EXPECT_EQ(r.countA, inA);
  EXPECT_EQ(r.intersects, both > 0);
  EXPECT_EQ(r.anded.count(), both);
  EXPECT_EQ(r.ored.count(), either);
  EXPECT_EQ(r.subtracted.count(), onlyA);
  EXPECT_EQ(r.selfAnded, a);
  EXPECT_EQ(r.selfOred, a);
  EXPECT_TRUE(r.selfSubtracted.none());
}

const std::size_t kSizes[] = {0,
                              1,
                              2,
                              63,
                              64,
                              65,
                              127,
                              128,
                              129,
                              255,
                              256,
                              257,
                              511,
                              512,
                              513,
                              1000,
                              2047,
                              2048,
                              2049,
                              4095,
                              4096,
                              4097,
                              7937,
                              8191,
                              8192,
                              8193,
                              64 * 64 * 64 - 1,
                              64 * 64 * 64,
                              64 * 64 * 64 + 1};

TEST(VoxelSet, EveryLevelGivesTheSameResultsBitForBit) {
  std::mt19937_64 rng(11);
  const auto levels = supportedSimdLevels();
  ASSERT_FALSE(levels.empty());
  ASSERT_EQ(levels.front(), SimdLevel::Portable);
  for (std::size_t bits : kSizes) {
    for (double density : {0.0, 0.02, 0.5, 0.98, 1.0}) {
      SCOPED_TRACE(testing::Message() << bits << " bits, density " << density);
      const VoxelSet a = randomSet(bits, density, rng), b = randomSet(bits, 0.5, rng);
      const Results portable = resultsOn(SimdLevel::Portable, a, b);
      expectMatchesBitTests(portable, a, b);
      for (SimdLevel level : levels) {
        SCOPED_TRACE(simdLevelName(level));
        EXPECT_TRUE(resultsOn(level, a, b) == portable);
      }
    }
  }
}

// intersects() exits early on vector paths: put a single common voxel at
// every position class (first word, block boundaries, the last partial vector).
TEST(VoxelSet, IntersectsFindsASingleCommonVoxelAnywhere) {
  std::mt19937_64 rng(12);
  for (std::size_t bits : {1u, 65u, 300u, 2048u + 64u * 5u + 7u, 4097u}) {
    const VoxelSet a = randomSet(bits, 0.5, rng), b = a.complemented();
    for (std::size_t p : {std::size_t(0), bits / 3, bits / 2, bits - 1}) {
      VoxelSet a1 = a, b1 = b;
      a1.set(p);
      b1.set(p);
      for (SimdLevel level : supportedSimdLevels()) {
        const ScopedSimdLevel scoped(level);
        SCOPED_TRACE(testing::Message()
                     << bits << " bits, voxel " << p << ", " << simdLevelName(level));
        EXPECT_FALSE(VoxelSet::intersects(a, b));
        EXPECT_TRUE(VoxelSet::intersects(a1, b1));
        EXPECT_EQ(VoxelSet::countAnd(a1, b1), 1u);
      }
    }
  }
}

// compress(mask) is gather(mask.members()) on every level, whatever the
// masks' densities and wherever the packed words start and end.
TEST(VoxelSet, CompressIsGatherOfTheMasksMembersOnEveryLevel) {
  std::mt19937_64 rng(13);
  for (std::size_t bits : kSizes) {
    for (double density : {0.0, 0.1, 0.5, 0.9, 1.0}) {
      const VoxelSet a = randomSet(bits, 0.5, rng), mask = randomSet(bits, density, rng);
      const VoxelSet expected = a.gather(mask.members());
      ASSERT_EQ(expected.size(), mask.count());
      for (SimdLevel level : supportedSimdLevels()) {
        const ScopedSimdLevel scoped(level);
        SCOPED_TRACE(testing::Message()
                     << bits << " bits, mask density " << density << ", " << simdLevelName(level));
        EXPECT_EQ(a.compress(mask), expected);
        EXPECT_EQ(mask.compress(mask), VoxelSet(mask.count()).complemented());
      }
    }
  }
}

}  // namespace
}  // namespace csgvox
