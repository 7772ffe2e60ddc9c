// Minimal oriented bounding box through CGAL's optimal bounding box.

// CGAL's optimal bounding box needs its Eigen support; Eigen is linked already.
#ifndef CGAL_EIGEN3_ENABLED
#define CGAL_EIGEN3_ENABLED 1
#endif

#include "primitives/bounding_box.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/optimal_bounding_box.h>
#include <tbb/parallel_for.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/principal_axes.h"

namespace csgvox {
namespace {

// Points whose least principal variance is below this fraction of the
// largest lie on a plane (for CGAL's search, which needs a solid hull).
constexpr double kPlanarVarianceRatio = 1e-10;

// Above this many points, those that cannot be corners of the convex hull
// are dropped before CGAL's search, which starts with the hull of all it is
// given (4 of the 4.3 s of a 1M-point scan); the filter's hull is that of
// about kHullSubsample of them.
constexpr std::size_t kHullFilterPoints = 20000;
constexpr std::size_t kHullSubsample = 4000;

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

// The points that may be corners of the convex hull of `points`, in their
// order (Akl and Toussaint's filter, with the hull of an even subsample as
// the inner polytope). A point in that hull or on its boundary that is not
// one of the subsample's points lies in it or inside a segment between two
// of its corners, so it is no corner of the whole hull. The test is exact
// (CGAL's filtered orientation predicate; a test in doubles settles the
// points well inside first), so the hull of what is kept, the subsample
// included, is exactly the hull of all the points. Deterministic.
std::vector<K::Point_3> hullCandidates(const std::vector<K::Point_3>& points) {
  const std::size_t step = std::max<std::size_t>(1, points.size() / kHullSubsample);
  std::vector<K::Point_3> sample;
  for (std::size_t i = 0; i < points.size(); i += step) sample.push_back(points[i]);
  CGAL::Surface_mesh<K::Point_3> inner;
  CGAL::convex_hull_3(sample.begin(), sample.end(), inner);
  if (inner.number_of_faces() < 4) return points;  // flat: nothing to drop
  double cx = 0.0, cy = 0.0, cz = 0.0, extent = 0.0;
  for (const auto v : inner.vertices()) {
    const K::Point_3& p = inner.point(v);
    cx += p.x(), cy += p.y(), cz += p.z();
    extent = std::max({extent, std::abs(p.x()), std::abs(p.y()), std::abs(p.z())});
  }
  const double count = double(inner.number_of_vertices());
  const K::Point_3 centre(cx / count, cy / count, cz / count);
  // Per face: its corners, the side its inside is on, and its outward plane
  // n.x = c in doubles, with a margin far above their rounding: a point
  // farther than it from the plane is on the side the doubles say, and the
  // exact predicate decides the points within it.
  struct Face {
    K::Point_3 a, b, c;
    CGAL::Orientation inside;
    double nx, ny, nz, offset, margin;
  };
  std::vector<Face> faces;
  for (const auto f : inner.faces()) {
    std::array<K::Point_3, 3> v;
    std::size_t k = 0;
    for (const auto h : CGAL::halfedges_around_face(inner.halfedge(f), inner)) {
      if (k < 3) v[k] = inner.point(inner.target(h));
      ++k;
    }
    Face face{v[0], v[1], v[2], CGAL::orientation(v[0], v[1], v[2], centre), 0, 0, 0, 0, 0};
    if (face.inside == CGAL::COPLANAR) return points;
    K::Vector_3 n = CGAL::cross_product(v[1] - v[0], v[2] - v[0]);
    const double length = std::sqrt(n.squared_length());
    if (!(length > 0.0)) return points;
    if (n * (centre - v[0]) > 0.0) n = -n;  // outward
    face.nx = n.x(), face.ny = n.y(), face.nz = n.z();
    face.offset = n * (v[0] - CGAL::ORIGIN);
    face.margin = 1e-9 * length * std::max(extent, 1e-300);
    faces.push_back(face);
  }
  std::vector<unsigned char> keep(points.size(), 0);
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) {
    const K::Point_3& p = points[i];
    if (i % step == 0) {  // a subsample point
      keep[i] = 1;
      return;
    }
    // Kept when outside some face's plane (on it or inside all: dropped).
    keep[i] = std::any_of(faces.begin(), faces.end(), [&](const Face& q) {
      const double t = q.nx * p.x() + q.ny * p.y() + q.nz * p.z() - q.offset;
      if (t < -q.margin) return false;
      if (t > q.margin) return true;
      return CGAL::orientation(q.a, q.b, q.c, p) == -q.inside;
    });
  });
  std::vector<K::Point_3> kept;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (keep[i]) kept.push_back(points[i]);
  }
  return kept;
}

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
  const std::size_t limit = options.maxSearchPoints > 0 ? options.maxSearchPoints : points.size();
  const std::size_t step = std::max<std::size_t>(1, (points.size() + limit - 1) / limit);
  std::vector<K::Point_3> searched;
  searched.reserve(points.size() / step + 1);
  for (std::size_t i = 0; i < points.size(); i += step) {
    searched.emplace_back(points[i].x(), points[i].y(), points[i].z());
  }
  if (options.hullFilter && searched.size() > kHullFilterPoints)
    searched = hullCandidates(searched);
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
