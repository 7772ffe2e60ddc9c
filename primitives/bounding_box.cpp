// Minimal oriented bounding box through CGAL's optimal bounding box.

// CGAL's optimal bounding box needs its Eigen support; Eigen is linked already.
#ifndef CGAL_EIGEN3_ENABLED
#define CGAL_EIGEN3_ENABLED 1
#endif

#include "primitives/bounding_box.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/optimal_bounding_box.h>

#include <Eigen/SVD>
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "core/principal_axes.h"

namespace csgvox {
namespace {

// Points whose least principal variance is below this fraction of the
// largest lie on a plane (for CGAL's search, which needs a solid hull).
constexpr double kPlanarVarianceRatio = 1e-10;

Mat3 rightHanded(Mat3 frame) {
  if (frame.determinant() < 0.0) frame.col(2) = -frame.col(2);
  return frame;
}

// The frame of the minimal box, orthonormal but of either handedness.
Mat3 anyHandedFrame(std::span<const Vec3> points, const MinimalBoxOptions& options) {
  const PrincipalAxes spread = principalAxes(points);
  const Mat3& principal = spread.axes;
  const Vec3& variances = spread.variances;
  if (points.size() < 4 || !(variances[2] > kPlanarVarianceRatio * variances[0])) {
    return principal;
  }
  // The search runs on the convex hull, which for points sampled exactly on
  // a convex surface holds nearly all of them: an even subset keeps it fast.
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  const std::size_t limit = options.maxSearchPoints > 0 ? options.maxSearchPoints : points.size();
  const std::size_t step = std::max<std::size_t>(1, (points.size() + limit - 1) / limit);
  std::vector<K::Point_3> searched;
  searched.reserve(points.size() / step + 1);
  for (std::size_t i = 0; i < points.size(); i += step) {
    searched.emplace_back(points[i].x(), points[i].y(), points[i].z());
  }
  K::Aff_transformation_3 transform;
  CGAL::oriented_bounding_box(searched, transform, CGAL::parameters::random_seed(options.seed));
  // The transformation rotates the points into the box's axis-aligned frame:
  // its rows are the box's axes.
  Mat3 rows;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) rows(i, j) = CGAL::to_double(transform.m(i, j));
  }
  if (!rows.allFinite() || !(rows.rowwise().norm().minCoeff() > 0.5)) return principal;
  // Re-orthonormalise (the transformation is a rotation up to rounding).
  const Eigen::JacobiSVD<Mat3> svd(rows, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return (svd.matrixU() * svd.matrixV().transpose()).transpose();
}

}  // namespace

Mat3 minimalBoxFrame(std::span<const Vec3> points, const MinimalBoxOptions& options) {
  return rightHanded(anyHandedFrame(points, options));
}

OrientedBox minimalOrientedBox(std::span<const Vec3> points, const MinimalBoxOptions& options) {
  if (points.size() < 4) throw std::invalid_argument("an oriented box needs at least 4 points");
  return boxAlong(points, anyHandedFrame(points, options));
}

}  // namespace csgvox
