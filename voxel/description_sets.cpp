#include "voxel/description_sets.h"

#include <tbb/parallel_for.h>

#include <array>
#include <vector>

#include "core/tree_program.h"

namespace csgvox {

namespace {

// V of `solid` into `voxels`; true when V holds a voxel of the grid's
// outermost layer.
bool fillSolidVoxels(const CsgTree& solid, const VoxelGrid& grid, VoxelSet& voxels) {
  voxels = VoxelSet(grid.voxelCount());
  std::array<int, 3> lo, hi;
  grid.voxelRange(solid.bounds(), lo, hi);
  if (lo[0] >= hi[0] || lo[1] >= hi[1] || lo[2] >= hi[2]) return false;
  const auto& dims = grid.dims();
  const TreeProgram program(solid);
  std::vector<Vec3> row(static_cast<std::size_t>(hi[0] - lo[0]));
  std::vector<double> f(row.size());
  bool exceeds = false;
  for (int k = lo[2]; k < hi[2]; ++k) {
    for (int j = lo[1]; j < hi[1]; ++j) {
      for (int i = lo[0]; i < hi[0]; ++i) row[std::size_t(i - lo[0])] = grid.center(i, j, k);
      program.values(row, f);
      const bool borderRow = j == 0 || k == 0 || j == dims[1] - 1 || k == dims[2] - 1;
      for (int i = lo[0]; i < hi[0]; ++i) {
        if (f[std::size_t(i - lo[0])] < 0.0) continue;
        voxels.set(grid.index(i, j, k));
        exceeds = exceeds || borderRow || i == 0 || i == dims[0] - 1;
      }
    }
  }
  return exceeds;
}

}  // namespace

VoxelSet solidVoxels(const CsgTree& solid, const VoxelGrid& grid) {
  VoxelSet voxels;
  fillSolidVoxels(solid, grid, voxels);
  return voxels;
}

DescriptionSet describe(const CsgTree& solid, const VoxelGrid& grid, const VoxelLabels& labels) {
  DescriptionSet d;
  d.exceedsGrid = fillSolidVoxels(solid, grid, d.voxels);
  d.plus = VoxelSet::countAnd(d.voxels, labels.inside);
  d.minus = d.voxels.count() - d.plus;
  return d;
}

std::vector<DescriptionSet> describeAll(std::span<const CsgTree> solids, const VoxelGrid& grid,
                                        const VoxelLabels& labels, const RunControl& control) {
  std::vector<DescriptionSet> out(solids.size());
  tbb::parallel_for(std::size_t(0), solids.size(), [&](std::size_t i) {
    if (!control.cancelled()) out[i] = describe(solids[i], grid, labels);
  });
  return out;
}

}  // namespace csgvox
