#pragma once
/// Simplifications of the union the voxel optimisation chose that keep its
/// voxels exactly: operations that change nothing go, and a subtraction
/// several members share is applied once to the whole union.

#include <cstdint>
#include <span>
#include <vector>

#include "optimize/union_member.h"

namespace csgvox {

/// Removes the actions that change no voxel of their member (last action
/// first), then the members whose voxels the others cover (smallest first).
/// `d` describes every candidate; voxel sets have `size` voxels. The union's
/// voxels are unchanged.
void dropNoOps(std::vector<UnionMember>& members, std::span<const DescriptionSet> d,
               std::size_t size);

/// Lifts shared subtractions: for each candidate that two or more members
/// subtract (in ascending index), removes those subtractions from every
/// member when subtracting the candidate once from the union (after those
/// lifted before it) gives the same voxels. Returns the lifted candidates in
/// the order they are to be subtracted from the union of `members`.
std::vector<std::uint32_t> liftSharedSubtractions(std::vector<UnionMember>& members,
                                                  std::span<const DescriptionSet> d,
                                                  std::size_t size);

}  // namespace csgvox
