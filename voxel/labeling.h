#pragma once
/// Inside/outside labels of the voxels of a grid, from an oriented scan.

#include "primitives/point_cloud.h"
#include "voxel/voxel_grid.h"
#include "voxel/voxel_set.h"

#include <string_view>

namespace csgvox {

/// How voxels are labelled.
enum class LabelMethod {
  /// Generalised winding number of the oriented points (Barnes-Hut
  /// approximation): robust to holes and noise.
  WindingNumber,
  /// Wu et al.'s vote: outside when more than epsilon of the K nearest points
  /// have normals facing the voxel centre.
  NormalVote,
};

/// Options of labelVoxels.
struct LabelOptions {
  LabelMethod method = LabelMethod::WindingNumber;  ///< labelling rule
  int neighbors = 50;              ///< NormalVote: K nearest points per voxel centre
  double epsilon = 0.8;            ///< NormalVote: outside when the facing fraction exceeds this
  double windingThreshold = 0.5;   ///< WindingNumber: inside when the winding number exceeds this
  double farFieldRatio = 2.0;      ///< WindingNumber: a cluster is approximated when farther than this many of its radii
  int areaNeighbors = 10;          ///< WindingNumber: neighbours used to estimate each point's area
};

/// Labels of every voxel of a grid.
struct VoxelLabels {
  VoxelSet inside;    ///< voxels labelled inside (includes every occupied voxel)
  VoxelSet occupied;  ///< voxels that hold at least one scan point
};

/// Labels the voxels of `grid` from the oriented points of `scan`. Voxels
/// holding points are inside (Wu's convention for boundary voxels).
/// @throw std::invalid_argument when the scan has no normals or is empty.
VoxelLabels labelVoxels(const VoxelGrid& grid, const PointCloud& scan,
                        const LabelOptions& options = {});

/// "winding" or "vote".
std::string_view labelMethodName(LabelMethod method);
/// Inverse of labelMethodName. @throw std::invalid_argument for other names.
LabelMethod labelMethodFromName(std::string_view name);

}  // namespace csgvox
