#include "optimize/union_member.h"

namespace csgvox {

VoxelSet memberVoxels(const UnionMember& member, std::span<const DescriptionSet> d,
                      std::size_t skipAction) {
  VoxelSet v = d[member.root].voxels;
  for (std::size_t a = 0; a < member.actions.size(); ++a) {
    if (a == skipAction) continue;
    const VoxelSet& tool = d[member.actions[a].primitive].voxels;
    if (member.actions[a].subtract) {
      v.subtract(tool);
    } else {
      v &= tool;
    }
  }
  return v;
}

VoxelSet unionVoxels(std::span<const UnionMember> members, std::size_t size) {
  VoxelSet v(size);
  for (const UnionMember& m : members) v |= m.voxels;
  return v;
}

}  // namespace csgvox
