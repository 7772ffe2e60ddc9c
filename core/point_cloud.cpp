#include "core/point_cloud.h"

namespace csgvox {

Aabb PointCloud::bounds() const {
  Aabb b;
  for (const Vec3& p : points) b.extend(p);
  return b;
}

PointCloud PointCloud::subset(std::span<const std::uint32_t> indices) const {
  PointCloud out;
  const bool withNormals = hasNormals();
  out.points.reserve(indices.size());
  if (withNormals) out.normals.reserve(indices.size());
  for (std::uint32_t i : indices) {
    out.points.push_back(points[i]);
    if (withNormals) out.normals.push_back(normals[i]);
  }
  return out;
}

}  // namespace csgvox
