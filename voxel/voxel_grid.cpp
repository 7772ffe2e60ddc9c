#include "voxel/voxel_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace csgvox {

VoxelGrid::VoxelGrid(const Vec3& origin, const Mat3& axes, double voxelSize,
                     std::array<int, 3> dims)
    : origin_(origin), axes_(axes), voxelSize_(voxelSize), dims_(dims) {}

VoxelGrid VoxelGrid::around(const OrientedBox& box, const GridOptions& options) {
  if (options.resolution < 2) throw std::invalid_argument("the grid resolution must be >= 2");
  const double longest = 2.0 * box.halfSize.maxCoeff();
  if (!(longest > 0.0) || !std::isfinite(longest)) {
    throw std::invalid_argument("cannot build a voxel grid around a degenerate box");
  }
  const double margin = std::max(0.0, options.marginVoxels);
  // The longest side (plus margins) holds `resolution` voxels.
  const double size = longest / std::max(1.0, options.resolution - 2.0 * margin);
  // A side that passes a whole number of voxels by under a hundredth of one
  // (the rounding of a box around fitted surfaces, a frame tilted by a few
  // microradians) gets no extra voxel: the grid is centred on the box, and
  // one voxel more would shift it by half a voxel, putting a layer of voxel
  // centres on every face of the part a whole number of voxels from its
  // ends, where the labels say inside or outside at random. What is cut
  // off lies in the margin (without one, only rounding is forgiven).
  const double slack = margin >= 0.01 ? 0.01 : 1e-9;
  std::array<int, 3> dims;
  for (int a = 0; a < 3; ++a) {
    dims[a] = std::max(1, int(std::ceil(2.0 * box.halfSize[a] / size + 2.0 * margin - slack)));
  }
  const Vec3 extent(dims[0] * size, dims[1] * size, dims[2] * size);
  const Vec3 origin = box.center - box.axes * (0.5 * extent);
  return VoxelGrid(origin, box.axes, size, dims);
}

std::size_t VoxelGrid::voxelOf(const Vec3& p) const {
  const Vec3 g = toGrid(p);
  // Compared before the cast: a point far off (or NaN) never reaches int.
  if (!(g.x() >= 0.0 && g.y() >= 0.0 && g.z() >= 0.0 && g.x() < dims_[0] && g.y() < dims_[1] &&
        g.z() < dims_[2])) {
    return npos;
  }
  return index(int(g.x()), int(g.y()), int(g.z()));
}

Vec3 VoxelGrid::center(std::size_t index) const {
  const std::size_t plane = std::size_t(dims_[0]) * dims_[1];
  const int k = int(index / plane);
  const std::size_t rest = index % plane;
  return center(int(rest % dims_[0]), int(rest / dims_[0]), k);
}

void VoxelGrid::voxelRange(const Aabb& b, std::array<int, 3>& lo, std::array<int, 3>& hi) const {
  Aabb g;
  if (!b.isBounded()) {
    lo = {0, 0, 0};
    hi = dims_;
    if (b.isEmpty()) hi = {0, 0, 0};
    return;
  }
  for (int c = 0; c < 8; ++c) {
    g.extend(toGrid(Vec3((c & 1) ? b.max.x() : b.min.x(), (c & 2) ? b.max.y() : b.min.y(),
                         (c & 4) ? b.max.z() : b.min.z())));
  }
  for (int a = 0; a < 3; ++a) {
    // Centre of voxel i is at i + 0.5.
    lo[a] = std::clamp(int(std::floor(g.min[a] - 0.5)), 0, dims_[a]);
    hi[a] = std::clamp(int(std::ceil(g.max[a] - 0.5)) + 1, 0, dims_[a]);
    if (hi[a] < lo[a]) hi[a] = lo[a];
  }
}

OrientedBox VoxelGrid::box() const {
  OrientedBox b;
  b.axes = axes_;
  b.halfSize = 0.5 * voxelSize_ * Vec3(dims_[0], dims_[1], dims_[2]);
  b.center = origin_ + axes_ * b.halfSize;
  return b;
}

}  // namespace csgvox
