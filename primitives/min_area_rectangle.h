#pragma once
/// The minimum-area bounding rectangle of 2D points (CGAL).

#include <Eigen/Core>
#include <vector>

namespace csgvox {

/// A rectangle's orientation and size: the unit direction of its longer side
/// and its side lengths (length >= width).
struct Rectangle2 {
  Eigen::Vector2d direction{1.0, 0.0};
  double length = 0.0;
  double width = 0.0;
};

/// Minimum-area bounding rectangle of the points (CGAL's convex_hull_2 and
/// min_rectangle_2). Collinear points give their segment (width 0); a single
/// position or no points, a rectangle of size 0 along x.
Rectangle2 minAreaRectangle(const std::vector<Eigen::Vector2d>& points);

}  // namespace csgvox
