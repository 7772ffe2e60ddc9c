// Minimal oriented bounding box through CGAL's optimal bounding box.

#include "primitives/bounding_box.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/optimal_bounding_box.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace csgvox {

OrientedBox minimalOrientedBox(std::span<const Vec3> points) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  if (points.size() < 4) throw std::invalid_argument("an oriented box needs at least 4 points");
  std::vector<K::Point_3> pts;
  pts.reserve(points.size());
  for (const Vec3& p : points) pts.emplace_back(p.x(), p.y(), p.z());
  K::Aff_transformation_3 t;
  CGAL::oriented_bounding_box(pts, t, CGAL::parameters::random_seed(1));
  // t maps the points into a frame where the box is axis-aligned: its rows
  // are the box's axes.
  Mat3 r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = CGAL::to_double(t.m(i, j));
  }
  // Re-orthonormalise (the transformation is a rotation up to rounding).
  Eigen::JacobiSVD<Mat3> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 axes = (svd.matrixU() * svd.matrixV().transpose()).transpose();
  return boxAlong(points, axes);
}

}  // namespace csgvox
