#pragma once
/// A regular voxel grid in an oriented frame (usually the scan's minimal
/// oriented bounding box), with `resolution` voxels along its longest side.

#include <array>
#include <cstddef>
#include <limits>
#include <span>

#include "core/oriented_box.h"

namespace csgvox {

/// Options of VoxelGrid::around.
struct GridOptions {
  int resolution = 64;      ///< voxels along the longest side of the box
  double marginVoxels = 2;  ///< empty margin added on every side, in voxels
};

/// A grid of cubic voxels. Voxel (i, j, k) spans
/// origin + axes * ([i, i+1] x [j, j+1] x [k, k+1]) * voxelSize.
class VoxelGrid {
 public:
  VoxelGrid() = default;
  VoxelGrid(const Vec3& origin, const Mat3& axes, double voxelSize, std::array<int, 3> dims);
  /// The grid covering `box` with the options' resolution and margin.
  /// @throw std::invalid_argument for a resolution < 2 or a degenerate box.
  static VoxelGrid around(const OrientedBox& box, const GridOptions& options = {});

  const Vec3& origin() const { return origin_; }
  const Mat3& axes() const { return axes_; }
  double voxelSize() const { return voxelSize_; }
  const std::array<int, 3>& dims() const { return dims_; }
  std::size_t voxelCount() const { return std::size_t(dims_[0]) * dims_[1] * dims_[2]; }

  /// Linear index of voxel (i, j, k); i varies fastest.
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k) * dims_[1] + std::size_t(j)) * dims_[0] + std::size_t(i);
  }
  /// World position of the centre of voxel (i, j, k).
  Vec3 center(int i, int j, int k) const {
    return origin_ + axes_ * (Vec3(i + 0.5, j + 0.5, k + 0.5) * voxelSize_);
  }
  /// World position of the centre of the voxel with linear index `index`.
  Vec3 center(std::size_t index) const;
  /// Grid coordinates (in voxels, continuous) of a world point.
  Vec3 toGrid(const Vec3& p) const { return axes_.transpose() * (p - origin_) / voxelSize_; }
  /// What voxelOf returns for a point outside the grid.
  static constexpr std::size_t npos = std::numeric_limits<std::size_t>::max();
  /// Linear index of the voxel holding the world point p (a point on a
  /// shared face belongs to the voxel above it), or npos when p lies outside
  /// the grid or is not finite.
  std::size_t voxelOf(const Vec3& p) const;
  /// Range of voxel indices [lo, hi) per axis whose centres may lie in the
  /// world-space box `b` (clamped to the grid; empty when outside).
  void voxelRange(const Aabb& b, std::array<int, 3>& lo, std::array<int, 3>& hi) const;
  /// The grid's extent as an oriented box.
  OrientedBox box() const;

 private:
  Vec3 origin_ = Vec3::Zero();
  Mat3 axes_ = Mat3::Identity();
  double voxelSize_ = 1.0;
  std::array<int, 3> dims_{0, 0, 0};
};

}  // namespace csgvox
