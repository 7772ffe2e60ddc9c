#include "primitives/min_area_rectangle.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_2.h>
#include <CGAL/min_quadrilateral_2.h>

#include <iterator>

namespace csgvox {

Rectangle2 minAreaRectangle(const std::vector<Eigen::Vector2d>& points) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using V2 = Eigen::Vector2d;
  std::vector<K::Point_2> in;
  in.reserve(points.size());
  for (const V2& p : points) in.emplace_back(p.x(), p.y());
  std::vector<K::Point_2> hull;  // counter-clockwise
  CGAL::convex_hull_2(in.begin(), in.end(), std::back_inserter(hull));
  auto vec = [](const K::Point_2& p) { return V2(p.x(), p.y()); };
  Rectangle2 r;
  if (hull.size() < 2) return r;
  if (hull.size() == 2) {  // collinear: the segment
    const V2 side = vec(hull[1]) - vec(hull[0]);
    return Rectangle2{side.normalized(), side.norm(), 0.0};
  }
  std::vector<K::Point_2> corners;
  CGAL::min_rectangle_2(hull.begin(), hull.end(), std::back_inserter(corners));
  const V2 a = vec(corners[1]) - vec(corners[0]);
  const V2 b = vec(corners[2]) - vec(corners[1]);
  return a.norm() >= b.norm() ? Rectangle2{a.normalized(), a.norm(), b.norm()}
                              : Rectangle2{b.normalized(), b.norm(), a.norm()};
}

}  // namespace csgvox
