#include <gtest/gtest.h>

#include <random>
#include <set>

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

}  // namespace
}  // namespace csgvox
