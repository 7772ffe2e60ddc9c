#include "optimize/union_simplification.h"

#include <algorithm>
#include <map>

namespace csgvox {

void dropNoOps(std::vector<UnionMember>& members, std::span<const DescriptionSet> d,
               std::size_t size) {
  for (UnionMember& m : members) {
    for (std::size_t a = m.actions.size(); a-- > 0;) {
      if (memberVoxels(m, d, a) == m.voxels) m.actions.erase(m.actions.begin() + long(a));
    }
  }
  const VoxelSet all = unionVoxels(members, size);
  // Try the smallest members first: they are the likeliest to be covered.
  std::vector<std::size_t> order(members.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return members[a].voxels.count() < members[b].voxels.count();
  });
  std::vector<char> gone(members.size(), 0);
  for (std::size_t i : order) {
    VoxelSet rest(size);
    for (std::size_t j = 0; j < members.size(); ++j) {
      if (j != i && !gone[j]) rest |= members[j].voxels;
    }
    if (rest == all) gone[i] = 1;
  }
  std::vector<UnionMember> kept;
  for (std::size_t i = 0; i < members.size(); ++i) {
    if (!gone[i]) kept.push_back(std::move(members[i]));
  }
  members = std::move(kept);
}

std::vector<std::uint32_t> liftSharedSubtractions(std::vector<UnionMember>& members,
                                                  std::span<const DescriptionSet> d,
                                                  std::size_t size) {
  const VoxelSet target = unionVoxels(members, size);
  std::map<std::uint32_t, int> uses;
  for (const UnionMember& m : members) {
    for (const SubtreeAction& a : m.actions) uses[a.primitive] += a.subtract ? 1 : 0;
  }
  std::vector<std::uint32_t> lifted;
  for (const auto& [prim, count] : uses) {
    if (count < 2) continue;
    std::vector<UnionMember> trial = members;
    for (UnionMember& m : trial) {
      std::erase_if(m.actions,
                    [&](const SubtreeAction& a) { return a.subtract && a.primitive == prim; });
      m.voxels = memberVoxels(m, d);
    }
    VoxelSet v = unionVoxels(trial, size);
    for (std::uint32_t l : lifted) v.subtract(d[l].voxels);
    v.subtract(d[prim].voxels);
    if (v == target) {
      members = std::move(trial);
      lifted.push_back(prim);
    }
  }
  return lifted;
}

}  // namespace csgvox
