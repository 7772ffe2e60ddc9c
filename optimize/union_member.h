#pragma once
/// An operand of the union the voxel optimisation builds: a root candidate
/// with the truncation actions phase 1 chose for it.

#include <cstdint>
#include <span>
#include <vector>

#include "optimize/subtree_selection.h"
#include "voxel/description_sets.h"

namespace csgvox {

/// A root candidate cut by its actions (applied in order), and the voxels
/// that leaves.
struct UnionMember {
  std::uint32_t root = 0;              ///< index of the root candidate
  std::vector<SubtreeAction> actions;  ///< the truncation, in order
  VoxelSet voxels;                     ///< the member's voxels (memberVoxels)
};

/// The voxels of `member` computed from the candidates' description sets
/// `d`, leaving out action `skipAction` (none by default).
VoxelSet memberVoxels(const UnionMember& member, std::span<const DescriptionSet> d,
                      std::size_t skipAction = std::size_t(-1));

/// The union of the members' voxels (each set of `size` voxels).
VoxelSet unionVoxels(std::span<const UnionMember> members, std::size_t size);

/// Primitives a member puts in the tree: its root and one per action.
inline std::size_t memberPrimitives(const UnionMember& member) { return 1 + member.actions.size(); }

}  // namespace csgvox
