#pragma once
/// The minimal oriented bounding box of a point set (CGAL).

#include "core/oriented_box.h"

#include <span>

namespace csgvox {

/// Minimal-volume oriented bounding box of points (CGAL's optimal bounding
/// box). Axes are ordered longest first and made right-handed.
/// @throw std::invalid_argument for fewer than 4 points.
OrientedBox minimalOrientedBox(std::span<const Vec3> points);

}  // namespace csgvox
