#include "optimize/union_refinement.h"

#include <algorithm>

namespace csgvox {
namespace {

// Removes members, one at a time, while that lowers the energy.
double pruneMembers(std::vector<UnionMember>& members, const VoxelSet& inside, double cost,
                    double energy) {
  for (bool improved = true; improved && members.size() > 1;) {
    improved = false;
    for (std::size_t i = 0; i < members.size(); ++i) {
      std::vector<UnionMember> trial = members;
      trial.erase(trial.begin() + long(i));
      const double e = refinementEnergy(trial, inside, cost);
      if (e < energy - 1e-9) {
        members = std::move(trial);
        energy = e;
        improved = true;
        break;
      }
    }
  }
  return energy;
}

}  // namespace

double refinementEnergy(std::span<const UnionMember> members, const VoxelSet& inside, double cost) {
  VoxelSet u(inside.size());
  std::size_t prims = 0;
  for (const UnionMember& m : members) {
    u |= m.voxels;
    prims += memberPrimitives(m);
  }
  const std::size_t disagree = VoxelSet::countAndNot(u, inside) + VoxelSet::countAndNot(inside, u);
  return cost * double(prims) + double(disagree);
}

void refineUnion(std::vector<UnionMember>& members, std::span<const UnionMember> extra,
                 std::span<const DescriptionSet> d, const VoxelSet& inside, double cost) {
  const std::size_t insideCount = inside.count();
  double energy = refinementEnergy(members, inside, cost);
  energy = pruneMembers(members, inside, cost, energy);
  const auto tryMove = [&](std::vector<UnionMember>& trial) {
    double e = refinementEnergy(trial, inside, cost);
    e = pruneMembers(trial, inside, cost, e);
    if (e < energy - 1e-9) {
      members = std::move(trial);
      energy = e;
      return true;
    }
    return false;
  };
  for (bool improved = true; improved;) {
    improved = false;
    for (std::size_t i = 0; i < members.size() && !improved; ++i) {
      for (std::size_t a = 0; a < members[i].actions.size() && !improved; ++a) {
        std::vector<UnionMember> trial = members;
        UnionMember& m = trial[i];
        m.actions.erase(m.actions.begin() + long(a));
        m.voxels = memberVoxels(m, d);
        improved = tryMove(trial);
      }
    }
    for (std::size_t k = 0; k < extra.size() && !improved; ++k) {
      const bool present = std::any_of(members.begin(), members.end(), [&](const UnionMember& m) {
        return m.root == extra[k].root && m.actions == extra[k].actions;
      });
      if (present || VoxelSet::countAnd(extra[k].voxels, inside) == 0) continue;
      std::vector<UnionMember> trial = members;
      trial.push_back(extra[k]);
      improved = tryMove(trial);
    }
    if (improved) continue;
    // The best new or replaced action over all members and candidates.
    std::size_t prims = 0;
    for (const UnionMember& m : members) prims += memberPrimitives(m);
    double bestEnergy = energy - 1e-9;
    std::size_t bestUnionMember = 0;
    std::size_t bestSlot = std::size_t(-1);  // -1: a new action, else the action replaced
    SubtreeAction bestAction;
    bool found = false;
    for (std::size_t i = 0; i < members.size(); ++i) {
      const UnionMember& m = members[i];
      VoxelSet rest(inside.size());
      for (std::size_t j = 0; j < members.size(); ++j) {
        if (j != i) rest |= members[j].voxels;
      }
      // Tries `base` (the member's voxels without the changed slot) cut by
      // candidate k, as the action in `slot`, with `count` primitives.
      const auto tryAction = [&](const VoxelSet& base, std::size_t slot, std::uint32_t k,
                                 bool subtract, std::size_t count) {
        VoxelSet v = subtract ? base - d[k].voxels : base & d[k].voxels;
        v |= rest;
        const double e = cost * double(count) + double(v.count() + insideCount) -
                         2.0 * double(VoxelSet::countAnd(v, inside));
        if (e < bestEnergy) {
          bestEnergy = e;
          bestUnionMember = i;
          bestSlot = slot;
          bestAction = SubtreeAction{k, subtract};
          found = true;
        }
      };
      for (std::uint32_t k = 0; k < d.size(); ++k) {
        if (k == m.root || !VoxelSet::intersects(d[k].voxels, m.voxels)) continue;
        for (const bool subtract : {true, false}) {
          tryAction(m.voxels, std::size_t(-1), k, subtract, prims + 1);
        }
      }
      // Or the best replacement of one action's candidate by another, with
      // the same operation (a better fit of the same surface).
      for (std::size_t a = 0; a < m.actions.size(); ++a) {
        const SubtreeAction old = m.actions[a];
        const VoxelSet without = memberVoxels(m, d, a);
        for (std::uint32_t k = 0; k < d.size(); ++k) {
          if (k == old.primitive || k == m.root || !VoxelSet::intersects(d[k].voxels, without)) {
            continue;
          }
          tryAction(without, a, k, old.subtract, prims);
        }
      }
    }
    if (found) {
      std::vector<UnionMember> trial = members;
      UnionMember& m = trial[bestUnionMember];
      if (bestSlot == std::size_t(-1)) {
        m.actions.push_back(bestAction);
      } else {
        m.actions[bestSlot] = bestAction;
      }
      m.voxels = memberVoxels(m, d);
      improved = tryMove(trial);
    }
  }
}

}  // namespace csgvox
