#pragma once
/// Principal component analysis of 3D points: mean, covariance and principal axes.

#include <cstdint>
#include <span>

#include "core/geometry.h"

namespace csgvox {

/// The spread of a point set. For an empty set everything is zero.
struct PrincipalAxes {
  Vec3 mean = Vec3::Zero();        ///< centroid, scan units
  Mat3 covariance = Mat3::Zero();  ///< sum of (p - mean)(p - mean)^T over n, squared units
  Mat3 axes = Mat3::Identity();    ///< unit principal directions (columns), largest spread
                                   ///< first, right-handed
  Vec3 variances = Vec3::Zero();   ///< eigenvalues of the covariance, same order as axes
  /// The direction of least spread (a plane's normal for points on a plane).
  Vec3 leastAxis() const { return axes.col(2); }
};

/// Principal axes of `points`.
PrincipalAxes principalAxes(std::span<const Vec3> points);

/// Principal axes of the points `points[i]` for i in `indices` (each index
/// must be < points.size()).
PrincipalAxes principalAxes(std::span<const Vec3> points, std::span<const std::uint32_t> indices);

}  // namespace csgvox
