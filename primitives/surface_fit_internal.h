#pragma once
/// Internal to the surface fit (surface_fitting.cpp, surface_starts.cpp,
/// point_reassignment.cpp, surface_fit.cpp) and the holes found from their
/// rims (rim_holes.cpp): helpers they share. Not part of the public API.

#include <cstdint>
#include <span>

#include "primitives/surface_fit.h"

namespace csgvox::surface_fit_detail {

/// Orients the surface as the majority of the points' normals: plane normal
/// flipped, or the convexity flag set.
void orientByNormals(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                     Surface& surface);

/// RMS orthogonal distance of the points to the surface (0 for no points).
double rmsDistance(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                   const Surface& surface);

/// True when the surface's parameters are finite and in their ranges.
bool validSurface(const Surface& s);

/// Kasa circle fit of the points `indices` projected on the plane spanned by
/// the unit vectors u, v through `origin`: `centre` (in that plane) and
/// `radius`; false when the points are collinear in that plane.
bool fitCircle(const PointCloud& cloud, std::span<const std::uint32_t> indices, const Vec3& origin,
               const Vec3& u, const Vec3& v, Vec3& centre, double& radius);

}  // namespace csgvox::surface_fit_detail
