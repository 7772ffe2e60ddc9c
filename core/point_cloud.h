#pragma once
/// A scan: points with (optional) unit outward normals.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// Points of a scan, in the scan's own coordinates and units. `normals` is
/// either empty or holds one unit outward normal per point.
struct PointCloud {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool hasNormals() const { return !normals.empty() && normals.size() == points.size(); }
  /// Axis-aligned bounds of the points.
  Aabb bounds() const;
  /// Length of the bounding-box diagonal, D: the scale every relative
  /// parameter refers to.
  double diagonal() const { return bounds().diagonal(); }
  /// The points at `indices` (each less than size()), in that order, with
  /// their normals when the cloud has them.
  PointCloud subset(std::span<const std::uint32_t> indices) const;
};

}  // namespace csgvox
