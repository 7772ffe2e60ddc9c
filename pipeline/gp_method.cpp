#include "pipeline/gp_method.h"

#include <optional>
#include <stdexcept>

namespace csgvox {

GpResult runGp(const PointCloud& scan, std::span<const Surface> surfaces, const GpOptions& options,
               const GenerationCallback& onGeneration, const VoxelTarget* target) {
  if (!scan.hasNormals()) throw std::invalid_argument("the gp method needs a scan with normals");
  GpResult out;
  // Checked before and after the library (0.7 s on 10 000 points, not
  // interruptible itself).
  const auto cancelled = [&] {
    if (options.evolve.control.cancelled()) out.search.stop = EvolveStop::Cancelled;
    return out.search.stop == EvolveStop::Cancelled;
  };
  if (cancelled()) return out;
  out.primitives = gpPrimitives(scan, surfaces, options.primitives);
  if (cancelled()) return out;
  const double diagonal = scan.diagonal();
  if (options.partition) {
    PartitionOptions po = options.partitioning;
    po.roughPoints = options.roughPoints;
    out.partitioned = evolvePartitioned(scan.points, scan.normals, diagonal, out.primitives.library,
                                        options.fitness, options.evolve, po, onGeneration, target);
    out.search = out.partitioned->search;
  } else {
    const FitnessModel model(scan.points, scan.normals, diagonal, out.primitives.library,
                             options.fitness, target);
    const std::optional<FitnessModel> rough =
        roughModel(model, scan.points, scan.normals, options.roughPoints, options.evolve.seed);
    out.search = evolve(model, {}, options.evolve, onGeneration, rough ? &*rough : nullptr);
  }
  out.tree = out.search.best;
  const Aabb& b = out.primitives.clipBox;
  const Aabb bounds = out.tree.bounds();
  if (!bounds.isEmpty() && !(b.contains(bounds.min) && b.contains(bounds.max))) {
    // As the baseline does: the solid is cut to the box around the scan, the
    // region where its clipped cylinders and cones are the unbounded ones.
    const CsgTree box = CsgTree::leaf(Box{b.center(), Mat3::Identity(), 0.5 * b.size()}, "bounds");
    out.tree = CsgTree::intersect({out.tree, box});
    out.clipped = true;
  }
  return out;
}

}  // namespace csgvox
