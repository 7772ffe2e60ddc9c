#pragma once
/// How well a CSG tree fits a scan. Distances are in scan units; the
/// `relative` figures divide them by the scan's bounding-box diagonal D.

#include <cstdint>

#include "core/csg_tree.h"
#include "core/point_cloud.h"

namespace csgvox {

/// Options of evaluateFit.
struct FitOptions {
  std::size_t surfaceSamples = 200000;  ///< points sampled on the tree's boundary
  double withinTolerance = 0.01;        ///< "close" threshold, fraction of D
  std::uint64_t seed = 1;               ///< seed of the boundary sampling
};

/// Fit metrics of a tree against a scan.
struct FitMetrics {
  std::size_t points = 0;  ///< scan points
  double diagonal = 0.0;   ///< D, the scan's bounding-box diagonal
  double rmse = 0.0;  ///< Wu Eq. 9: RMS distance of each point to its nearest primitive surface
  double surfaceRmse = 0.0;     ///< RMS distance of the points to the solid's boundary
  double meanDistance = 0.0;    ///< mean distance of the points to the solid's boundary
  double maxDistance = 0.0;     ///< largest distance of a point to the solid's boundary
  double chamfer = 0.0;         ///< symmetric Chamfer distance (mean of both directions' means)
  double withinFraction = 0.0;  ///< fraction of points within withinTolerance*D of the boundary
  double normalAgreement =
      0.0;  ///< mean cosine between scan normals and the solid's outward normals
  double normalsWithin10Deg = 0.0;  ///< fraction of points whose normal is within 10 degrees
  bool hasNormals = false;          ///< false when the scan had no normals (normal figures are 0)
  double surfaceArea = 0.0;         ///< estimated boundary area of the tree
};

/// Computes the fit of `tree` to `scan`. Distances to the boundary use dense
/// samples of the boundary refined by their tangent planes, so they are
/// accurate to well below the sampling spacing on smooth regions.
/// @throw std::invalid_argument if the scan is empty or the tree cannot be sampled.
FitMetrics evaluateFit(const CsgTree& tree, const PointCloud& scan, const FitOptions& options = {});

}  // namespace csgvox
