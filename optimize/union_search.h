#pragma once
/// The final union search of the voxel optimisation. Phase 1 builds each
/// subtree for its own root against its own neighbours and phase 2 then
/// picks members independently among the subtrees free of outside voxels.
/// So a root that cut too much gets its loss covered by extra members, a
/// subtree a few mislabelled voxels short of clean is never offered, and an
/// action that only pays for the union as a whole (a chamfer cone cutting a
/// boss that another member's fillet meets) is never tried. A local search
/// over the whole union repairs all three.

#include <span>
#include <vector>

#include "optimize/union_member.h"

namespace csgvox {

/// Energy of a whole union for the final search: `cost` voxels per
/// primitive plus every voxel where the union and the labels `inside`
/// disagree. It is Eq. 4 and Eq. 6 made global: an action or member pays for
/// itself when it corrects about `cost` voxels, the same rule as
/// minFeatureVoxels.
double unionSearchEnergy(std::span<const UnionMember> members, const VoxelSet& inside, double cost);

/// Lowers unionSearchEnergy(members, inside, cost) by local search with five
/// moves, each followed by removing, one at a time, the members whose
/// removal lowers the energy: drop one action of a member; add one of
/// `extra` (in the construction: every subtree phase 1 built, clean or not,
/// and every bare candidate) as a member; add one candidate to a member as
/// an intersection or a subtraction, or put one in place of an action's
/// candidate with the same operation (the best such move of each round).
/// `d` describes every candidate. A move is kept only when the energy falls,
/// so the search ends; the first improving move is taken, in that order.
void searchUnion(std::vector<UnionMember>& members, std::span<const UnionMember> extra,
                 std::span<const DescriptionSet> d, const VoxelSet& inside, double cost);

}  // namespace csgvox
