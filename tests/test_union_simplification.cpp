// Simplifications that keep the union's voxels (optimize/union_simplification.h)
// on one-dimensional voxel sets.

#include <gtest/gtest.h>

#include <vector>

#include "optimize/union_simplification.h"
#include "union_member_fixtures.h"

namespace csgvox {
namespace {

using test::described;
using test::member;
using test::range;
constexpr std::size_t kSize = test::kLineSize;

// Two blocks [0, 40) and [50, 90), and a slot [30, 60) cut from both.
const std::vector<DescriptionSet> kParts{described(0, 40),  described(50, 90), described(30, 60),
                                         described(40, 50), described(60, 70), described(10, 20)};

TEST(LiftSharedSubtractions, LiftsASubtractionTwoMembersShare) {
  std::vector<UnionMember> members{member(0, {{2, true}}, kParts), member(1, {{2, true}}, kParts)};
  const VoxelSet before = unionVoxels(members, kSize);
  EXPECT_EQ(before, range(0, 30) | range(60, 90));
  const std::vector<std::uint32_t> lifted = liftSharedSubtractions(members, kParts, kSize);
  EXPECT_EQ(lifted, std::vector<std::uint32_t>{2});
  ASSERT_EQ(members.size(), 2u);
  EXPECT_TRUE(members[0].actions.empty());
  EXPECT_TRUE(members[1].actions.empty());
  EXPECT_EQ(members[0].voxels, range(0, 40));
  EXPECT_EQ(unionVoxels(members, kSize) - kParts[2].voxels, before);
}

TEST(LiftSharedSubtractions, KeepsASubtractionThatWouldCutAThirdMember) {
  // [40, 50) is a member of its own: cutting the slot from the whole union
  // would remove it.
  std::vector<UnionMember> members{member(0, {{2, true}}, kParts), member(1, {{2, true}}, kParts),
                                   member(3, {}, kParts)};
  const std::vector<UnionMember> before = members;
  EXPECT_TRUE(liftSharedSubtractions(members, kParts, kSize).empty());
  ASSERT_EQ(members.size(), 3u);
  for (std::size_t i = 0; i < members.size(); ++i) {
    EXPECT_EQ(members[i].actions, before[i].actions);
    EXPECT_EQ(members[i].voxels, before[i].voxels);
  }
}

TEST(LiftSharedSubtractions, LeavesASubtractionOnlyOneMemberMakes) {
  std::vector<UnionMember> members{member(0, {{2, true}}, kParts), member(1, {}, kParts)};
  EXPECT_TRUE(liftSharedSubtractions(members, kParts, kSize).empty());
  EXPECT_EQ(members[0].actions, (std::vector<SubtreeAction>{{2, true}}));
}

TEST(DropNoOps, RemovesAnIdleActionAndACoveredMember) {
  // Cutting [60, 70) from [0, 40) changes nothing; [10, 20) lies in [0, 40).
  std::vector<UnionMember> members{member(0, {{4, true}}, kParts), member(5, {}, kParts),
                                   member(1, {}, kParts)};
  const VoxelSet before = unionVoxels(members, kSize);
  dropNoOps(members, kParts, kSize);
  ASSERT_EQ(members.size(), 2u);
  EXPECT_EQ(members[0].root, 0u);
  EXPECT_TRUE(members[0].actions.empty());
  EXPECT_EQ(members[1].root, 1u);
  EXPECT_EQ(unionVoxels(members, kSize), before);
}

}  // namespace
}  // namespace csgvox
