// The final union search (optimize/union_search.h) on one-dimensional
// voxel sets: each case has one move that pays, and the search must make it.

#include <gtest/gtest.h>

#include <vector>

#include "optimize/union_search.h"
#include "union_member_fixtures.h"

namespace csgvox {
namespace {

using test::described;
using test::member;
using test::range;
constexpr double kCost = 8.0;  // voxels a primitive must correct to pay

TEST(UnionSearchEnergy, CountsPrimitivesAndDisagreeingVoxels) {
  const std::vector<DescriptionSet> d{described(0, 50), described(40, 60)};
  const VoxelSet inside = range(0, 55);
  // [0, 50): 5 inside voxels missed, 2 primitives.
  EXPECT_DOUBLE_EQ(unionSearchEnergy(std::vector{member(0, {}, d)}, inside, kCost), kCost + 5);
  // [0, 60): 5 outside voxels covered, 2 primitives.
  EXPECT_DOUBLE_EQ(
      unionSearchEnergy(std::vector{member(0, {}, d), member(1, {}, d)}, inside, kCost),
      2 * kCost + 5);
  // [0, 40) by cutting [40, 60) away: 15 missed.
  EXPECT_DOUBLE_EQ(unionSearchEnergy(std::vector{member(0, {{1, true}}, d)}, inside, kCost),
                   2 * kCost + 15);
}

TEST(SearchUnion, DropsAnActionThatDoesNotPay) {
  const std::vector<DescriptionSet> d{described(0, 100), described(90, 100)};
  std::vector<UnionMember> members{member(0, {{1, true}}, d)};
  searchUnion(members, {}, d, range(0, 100), kCost);
  ASSERT_EQ(members.size(), 1u);
  EXPECT_TRUE(members[0].actions.empty());
  EXPECT_EQ(members[0].voxels, range(0, 100));
}

TEST(SearchUnion, AddsTheSubtractionThatPays) {
  const std::vector<DescriptionSet> d{described(0, 100), described(80, 100)};
  std::vector<UnionMember> members{member(0, {}, d)};
  searchUnion(members, {}, d, range(0, 80), kCost);
  ASSERT_EQ(members.size(), 1u);
  EXPECT_EQ(members[0].actions, (std::vector<SubtreeAction>{{1, true}}));
  EXPECT_EQ(members[0].voxels, range(0, 80));
}

TEST(SearchUnion, ReplacesAnActionsCandidateByABetterFit) {
  // Cutting [85, 100) leaves 5 voxels; [80, 100) fits the inside exactly.
  // Adding it as a second cut would cost a primitive for those 5 voxels.
  const std::vector<DescriptionSet> d{described(0, 100), described(85, 100), described(80, 100)};
  std::vector<UnionMember> members{member(0, {{1, true}}, d)};
  searchUnion(members, {}, d, range(0, 80), kCost);
  ASSERT_EQ(members.size(), 1u);
  EXPECT_EQ(members[0].actions, (std::vector<SubtreeAction>{{2, true}}));
  EXPECT_EQ(members[0].voxels, range(0, 80));
}

TEST(SearchUnion, PrunesARedundantMemberAndAddsAMissingOne) {
  const std::vector<DescriptionSet> d{described(0, 50), described(60, 90), described(10, 20)};
  const VoxelSet inside = range(0, 50) | range(60, 90);
  std::vector<UnionMember> members{member(0, {}, d), member(2, {}, d)};
  const std::vector<UnionMember> extra{member(1, {}, d), member(2, {}, d)};
  searchUnion(members, extra, d, inside, kCost);
  ASSERT_EQ(members.size(), 2u);
  EXPECT_EQ(members[0].root, 0u);
  EXPECT_EQ(members[1].root, 1u);
  EXPECT_DOUBLE_EQ(unionSearchEnergy(members, inside, kCost), 2 * kCost);
}

TEST(SearchUnion, KeepsAnOptimalUnion) {
  // A cut of 5 voxels costs more than the 5 voxels it would correct.
  const std::vector<DescriptionSet> d{described(0, 100), described(95, 100)};
  std::vector<UnionMember> members{member(0, {}, d)};
  searchUnion(members, {}, d, range(0, 95), kCost);
  ASSERT_EQ(members.size(), 1u);
  EXPECT_TRUE(members[0].actions.empty());
}

}  // namespace
}  // namespace csgvox
