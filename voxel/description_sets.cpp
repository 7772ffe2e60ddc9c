#include "voxel/description_sets.h"

#include <tbb/parallel_for.h>

namespace csgvox {

DescriptionSet describe(const CsgTree& solid, const VoxelGrid& grid, const VoxelLabels& labels) {
  DescriptionSet d;
  d.voxels = VoxelSet(grid.voxelCount());
  std::array<int, 3> lo, hi;
  grid.voxelRange(solid.bounds(), lo, hi);
  const auto& dims = grid.dims();
  for (int k = lo[2]; k < hi[2]; ++k) {
    for (int j = lo[1]; j < hi[1]; ++j) {
      for (int i = lo[0]; i < hi[0]; ++i) {
        if (solid.value(grid.center(i, j, k)) < 0.0) continue;
        d.voxels.set(grid.index(i, j, k));
        if (i == 0 || j == 0 || k == 0 || i == dims[0] - 1 || j == dims[1] - 1 ||
            k == dims[2] - 1) {
          d.exceedsGrid = true;
        }
      }
    }
  }
  d.plus = VoxelSet::countAnd(d.voxels, labels.inside);
  d.minus = d.voxels.count() - d.plus;
  return d;
}

std::vector<DescriptionSet> describeAll(std::span<const CsgTree> solids, const VoxelGrid& grid,
                                        const VoxelLabels& labels) {
  std::vector<DescriptionSet> out(solids.size());
  tbb::parallel_for(std::size_t(0), solids.size(),
                    [&](std::size_t i) { out[i] = describe(solids[i], grid, labels); });
  return out;
}

}  // namespace csgvox
