#pragma once
/// The minimal oriented bounding box of a point set (CGAL).

#include <cstddef>
#include <cstdint>
#include <span>

#include "core/oriented_box.h"

namespace csgvox {

/// Options of minimalBoxFrame and minimalOrientedBox.
struct MinimalBoxOptions {
  std::uint32_t seed = 1;           ///< seed of CGAL's randomised search (same seed, same box)
  std::size_t maxSearchPoints = 0;  ///< the orientation is searched on at most this many evenly
                                    ///< spread points (count; 0 = all points)
  bool hullFilter = true;  ///< above 20 000 points, drop those that cannot be corners of the
                           ///< convex hull before the search (the same box, found sooner)
};

/// Axes (columns, orthonormal, right-handed) of the minimal-volume oriented
/// bounding box of the points (CGAL's optimal bounding box), in the order
/// CGAL reports them. For fewer than four points, or points (nearly) on a
/// plane, where the search is undefined: their principal axes.
Mat3 minimalBoxFrame(std::span<const Vec3> points, const MinimalBoxOptions& options = {});

/// Minimal-volume oriented bounding box of points: the box of every point
/// along minimalBoxFrame's axes, ordered longest first and right-handed.
/// @throw std::invalid_argument for fewer than 4 points.
OrientedBox minimalOrientedBox(std::span<const Vec3> points, const MinimalBoxOptions& options = {});

}  // namespace csgvox
