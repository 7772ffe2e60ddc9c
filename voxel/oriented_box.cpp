// Minimal oriented bounding box through CGAL's optimal bounding box.

#include "voxel/voxel_grid.h"

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

OrientedBox boxAlong(std::span<const Vec3> points, const Mat3& frame) {
  const Mat3& axes = frame;
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& p : points) {
    const Vec3 q = axes.transpose() * p;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  Vec3 half = 0.5 * (hi - lo);
  const Vec3 mid = 0.5 * (hi + lo);
  // Order the axes longest first, keep the frame right-handed.
  std::array<int, 3> order{0, 1, 2};
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return half[a] > half[b]; });
  OrientedBox box;
  for (int i = 0; i < 3; ++i) {
    box.axes.col(i) = axes.col(order[i]);
    box.halfSize[i] = half[order[i]];
  }
  if (box.axes.determinant() < 0.0) box.axes.col(2) = -box.axes.col(2);
  box.center = axes * mid;
  return box;
}

}  // namespace csgvox
