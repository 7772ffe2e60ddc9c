#include "pipeline/finish.h"

#include <chrono>
#include <stdexcept>

#include "voxel/description_sets.h"

namespace csgvox {
namespace {

Fitness fitnessOf(const PointCloud& scan, const CsgTree& tree, const FitnessOptions& options,
                  const VoxelTarget* voxels) {
  const PrimitiveLibrary library = PrimitiveLibrary::ofTree(tree);
  const FitnessModel model(scan.points, scan.normals, scan.diagonal(), library, options,
                           options.voxelWeight > 0.0 ? voxels : nullptr);
  return model.evaluate(library.adopt(tree));
}

double voxelIou(const CsgTree& tree, const VoxelTarget& voxels) {
  return VoxelSet::iou(solidVoxels(tree, voxels.grid), voxels.inside);
}

}  // namespace

FinishResult finishTree(const PointCloud& scan, const CsgTree& tree, const VoxelTarget* voxels,
                        const FinishOptions& options) {
  if (!scan.hasNormals()) throw std::invalid_argument("the finish needs a scan with normals");
  if (tree.empty()) throw std::invalid_argument("the finish needs a tree");
  const auto start = std::chrono::steady_clock::now();
  FinishResult out;
  out.tree = tree;

  TreeFitOptions fo;
  fo.operations = options.operations;
  fo.sardfRadius = options.fitness.sardfRadius;
  fo.distanceTolerance = options.fitness.distanceTolerance;
  fo.lossScale = options.lossScale;
  fo.nearDistance = options.nearDistance;
  fo.maxIterations = options.maxIterations;
  fo.maxPoints = options.maxPoints;
  fo.control = options.control;
  out.fit = fitTreeParameters(scan, tree, fo);
  if (out.fit.cancelled) {
    out.cancelled = true;
    out.fit.tree = tree;
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  }
  out.ran = out.fit.iterations > 0;
  out.before = fitnessOf(scan, tree, options.fitness, voxels);
  out.after = out.before;
  if (voxels) out.voxelIouBefore = out.voxelIouAfter = voxelIou(tree, *voxels);
  if (out.ran) {
    out.after = fitnessOf(scan, out.fit.tree, options.fitness, voxels);
    if (voxels) out.voxelIouAfter = voxelIou(out.fit.tree, *voxels);
    // A fit that moves nothing by more than 1e-6·D only rounds the input:
    // the input is kept as it is.
    out.accepted = out.fit.primitivesChanged > 0 && out.after.total >= out.before.total &&
                   out.voxelIouAfter >= out.voxelIouBefore;
  }
  if (out.accepted) {
    out.tree = out.fit.tree;
    out.primitivesChanged = out.fit.primitivesChanged;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace csgvox
