#pragma once
/// The hybrid method's last step: every primitive parameter of the final
/// tree is refined on the scan points through the tree's field
/// (primitives/tree_fitting.h), with the regularised relations kept exact,
/// and the fitted tree is kept only when the whole tree's fitness does not
/// get worse and its voxels agree with the labels at least as well.

#include <cstddef>

#include "core/csg_tree.h"
#include "core/point_cloud.h"
#include "evolve/fitness.h"
#include "primitives/tree_fitting.h"

namespace csgvox {

/// Options of finishTree().
struct FinishOptions {
  bool enabled = false;       ///< run the finish (reconstruct(): hybrid method only); off by
                              ///< default: it lowered noisy thin_tray's IoU by 0.003
  int maxIterations = 25;     ///< Levenberg-Marquardt iterations at most (count)
  double lossScale = 1.0;     ///< Huber scale of the point residuals, in εd
  double nearDistance = 3.0;  ///< only points this close to the tree's surface drive it, in εd
  SetOperationKind operations = SetOperationKind::MinMax;  ///< field the residuals go through
                                                           ///< (see primitives/tree_fitting.h)
  std::size_t maxPoints = 20000;  ///< more points than this are thinned to an even subset (count)
  /// The fitness that judges the result (reconstruct() sets it to the
  /// hybrid refinement's).
  FitnessOptions fitness = {.voxelWeight = 1.0};
  /// Past its deadline the fit keeps the parameters it has reached; a
  /// cancel request stops it and keeps the input tree (reconstruct() sets it).
  RunControl control;
};

/// What finishTree() did.
struct FinishResult {
  CsgTree tree;                       ///< the fitted tree if accepted, else the input
  bool ran = false;                   ///< the fit ran (enough points near the surface)
  bool accepted = false;              ///< the fitted parameters were kept
  bool cancelled = false;             ///< options.control was cancelled: the input is kept
  TreeFitResult fit;                  ///< the fit's own figures (residual RMS, points, ...)
  Fitness before;                     ///< the input tree's fitness on all points
  Fitness after;                      ///< the fitted tree's (accepted or not)
  double voxelIouBefore = 0.0;        ///< the input tree's voxels against the inside labels
  double voxelIouAfter = 0.0;         ///< the fitted tree's
  std::size_t primitivesChanged = 0;  ///< leaves whose primitive moved (0 unless accepted)
  double seconds = 0.0;               ///< wall time
};

/// Refines the parameters of `tree` on an oriented scan and keeps them when
/// some primitive moved by more than 1e-6·D, options.fitness does not drop
/// and the voxel IoU against `voxels`' labels does not drop (without
/// `voxels`, the fitness alone decides).
/// @throw std::invalid_argument when the scan has no normals or the tree is empty.
FinishResult finishTree(const PointCloud& scan, const CsgTree& tree, const VoxelTarget* voxels,
                        const FinishOptions& options = {});

}  // namespace csgvox
