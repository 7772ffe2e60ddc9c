#pragma once
/// Description sets of candidate solids on a labelled voxel grid (Wu §4.1):
/// V = voxels whose centre lies in the solid, V+ = V ∩ inside,
/// V− = V ∩ outside, and μ = whether the solid reaches the grid's border.

#include <span>
#include <vector>

#include "core/csg_tree.h"
#include "voxel/labeling.h"

namespace csgvox {

/// The description of one candidate solid.
struct DescriptionSet {
  VoxelSet voxels;           ///< V: voxels whose centre is in the solid (f >= 0)
  std::size_t plus = 0;      ///< |V+| = |V ∩ inside|
  std::size_t minus = 0;     ///< |V−| = |V ∩ outside|
  bool exceedsGrid = false;  ///< μ: the solid reaches the outermost layer of voxels
};

/// V alone: the voxels of `grid` whose centre lies in `solid` (f >= 0). Only
/// voxels inside the solid's bounds are evaluated, a row of them at a time.
VoxelSet solidVoxels(const CsgTree& solid, const VoxelGrid& grid);

/// Computes the description of `solid`. Only voxels inside the solid's
/// bounds are evaluated.
DescriptionSet describe(const CsgTree& solid, const VoxelGrid& grid, const VoxelLabels& labels);

/// Descriptions of many solids, in parallel; the result is in input order.
/// Once `control` is cancelled the remaining solids are skipped (left
/// empty: the result is then unusable).
std::vector<DescriptionSet> describeAll(std::span<const CsgTree> solids, const VoxelGrid& grid,
                                        const VoxelLabels& labels, const RunControl& control = {});

}  // namespace csgvox
