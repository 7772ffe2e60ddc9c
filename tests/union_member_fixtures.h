#pragma once
/// One-dimensional candidates and union members for the tests of the union
/// search and its simplifications: voxel i of a 100-voxel universe.

#include <vector>

#include "optimize/union_member.h"

namespace csgvox::test {

/// Voxels in the universe of the fixtures.
inline constexpr std::size_t kLineSize = 100;

/// The voxels [from, to).
inline VoxelSet range(std::size_t from, std::size_t to) {
  VoxelSet s(kLineSize);
  for (std::size_t i = from; i < to; ++i) s.set(i);
  return s;
}

/// A candidate whose voxels are [from, to).
inline DescriptionSet described(std::size_t from, std::size_t to) {
  DescriptionSet d;
  d.voxels = range(from, to);
  return d;
}

/// Candidate `root` cut by `actions`, with its voxels.
inline UnionMember member(std::uint32_t root, std::vector<SubtreeAction> actions,
                          const std::vector<DescriptionSet>& d) {
  UnionMember m{root, std::move(actions), {}};
  m.voxels = memberVoxels(m, d);
  return m;
}

}  // namespace csgvox::test
