#pragma once
/// Seeded random voxel sets for the optimisation tests.

#include <algorithm>
#include <random>

#include "voxel/voxel_set.h"

namespace csgvox::test {

/// A blob-like set of `bits` voxels: the union of `intervals` random
/// intervals of 1 to `maxLen` voxels, so that sets overlap in structured
/// ways as primitives do.
inline VoxelSet randomSet(std::size_t bits, std::mt19937_64& rng, int intervals,
                          std::size_t maxLen) {
  VoxelSet s(bits);
  std::uniform_int_distribution<std::size_t> start(0, bits - 1), len(1, maxLen);
  for (int k = 0; k < intervals; ++k) {
    const std::size_t a = start(rng), l = len(rng);
    for (std::size_t i = a; i < std::min(bits, a + l); ++i) s.set(i);
  }
  return s;
}

}  // namespace csgvox::test
