#include "io/point_arrays.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/principal_axes.h"
#include "io/errors.h"
#include "primitives/normal_estimation.h"
#include "primitives/outlier_removal.h"

namespace csgvox {

void checkReadOptions(const ReadOptions& options) {
  if (options.normalNeighbors < 6) {
    throw std::invalid_argument("ReadOptions::normalNeighbors must be at least 6");
  }
  if (!(options.minNormalAgreement >= 0.0 && options.minNormalAgreement <= 1.0)) {
    throw std::invalid_argument("ReadOptions::minNormalAgreement must be in 0..1");
  }
}

namespace {

// A cloud no thicker than this many times its noise is one flat face.
constexpr double kFlatNoise = 3.0;
// ... and has more than this fraction of its points within half its
// thickness of its middle plane (0.38 for Gaussian noise, 0 for two layers).
constexpr double kFlatMiddle = 0.2;

/// Removes the outliers of a point cloud (with their normals) and counts
/// them; rejects a cloud that is one flat face.
/// @throw ParseError when all points lie on one plane, within the noise.
void prepareCloud(Scan& scan, const std::string& source) {
  const Outliers outliers = findOutliers(scan.cloud.points);
  if (outliers.count() > 0) {
    PointCloud kept;
    const bool normals = scan.cloud.hasNormals();
    for (std::size_t i = 0; i < scan.cloud.size(); ++i) {
      if (outliers.outlier[i]) continue;
      kept.points.push_back(scan.cloud.points[i]);
      if (normals) kept.normals.push_back(scan.cloud.normals[i]);
    }
    scan.cloud = std::move(kept);
    scan.info.outliersRemoved = outliers.count();
    scan.info.offSurfaceRemoved = outliers.offSurface;
  }
  const std::size_t n = scan.cloud.size();
  const PrincipalAxes axes = principalAxes(scan.cloud.points);
  const double thickness = std::sqrt(std::max(0.0, axes.variances[2]));
  // One face spreads about its plane like noise; the two faces of a plate
  // thinner than the neighbourhoods (which then read its thickness as
  // noise) leave few points near the middle plane.
  const Vec3 across = axes.leastAxis();
  std::size_t middle = 0;
  for (const Vec3& p : scan.cloud.points) {
    middle += std::abs(across.dot(p - axes.mean)) < 0.5 * thickness;
  }
  if (axes.variances[1] > 0.0 && thickness <= kFlatNoise * outliers.noise &&
      double(middle) > kFlatMiddle * double(n)) {
    char within[64];
    std::snprintf(within, sizeof(within), "%.3g", thickness);
    throw ParseError(source + ": all " + std::to_string(n) + " points lie on one plane (within " +
                     within + ", the scan's noise): one flat face bounds no solid");
  }
}

}  // namespace

void completeNormals(Scan& scan, const std::string& source, const ReadOptions& options) {
  if (scan.info.fromMesh) return;
  if (options.removeOutliers) prepareCloud(scan, source);
  if (scan.cloud.hasNormals()) {
    // Normals that mostly disagree with the surface (random ones) would
    // leave detection nothing to find, slowly: they are estimated instead.
    scan.info.normalAgreement = normalAgreement(scan.cloud, options.normalNeighbors);
    if (scan.info.normalAgreement >= options.minNormalAgreement) return;
    scan.info.normalsReplaced = true;
  }
  const std::size_t n = scan.cloud.size();
  if (n <= static_cast<std::size_t>(options.normalNeighbors)) {
    throw ParseError(source + ": has only " + std::to_string(n) +
                     " points, too few to estimate normals from " +
                     std::to_string(options.normalNeighbors) + " neighbours");
  }
  try {
    estimateNormals(scan.cloud, options.normalNeighbors);
  } catch (const std::invalid_argument& e) {
    // Points that span no surface (all at one position, on a line).
    throw ParseError(source + ": " + e.what());
  }
  scan.info.normalsEstimated = true;
}

Scan scanFromArrays(std::vector<Vec3> points, std::vector<Vec3> normals, const std::string& source,
                    const ReadOptions& options) {
  if (!normals.empty() && normals.size() != points.size()) {
    throw ParseError(source + ": " + std::to_string(normals.size()) + " normals for " +
                     std::to_string(points.size()) + " points");
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw ParseError(source + ": point " + std::to_string(i + 1) +
                       " has a non-finite coordinate");
    }
  }
  for (std::size_t i = 0; i < normals.size(); ++i) {
    Vec3& normal = normals[i];
    const std::string what = "point " + std::to_string(i + 1);
    if (!normal.allFinite()) throw ParseError(source + ": " + what + " has a non-finite normal");
    const double length = normal.norm();
    if (!(length > 1e-12)) throw ParseError(source + ": " + what + " has a zero-length normal");
    if (std::abs(length - 1.0) > 1e-9) normal /= length;
  }
  const std::size_t minimum = std::max<std::size_t>(options.minPoints, 1);
  if (points.size() < minimum) {
    throw ParseError(source + ": has " + std::to_string(points.size()) + " points; at least " +
                     std::to_string(minimum) + " are needed");
  }
  checkReadOptions(options);
  Scan scan;
  scan.cloud.points = std::move(points);
  scan.cloud.normals = std::move(normals);
  scan.info.format = "array";
  scan.info.pointsRead = scan.cloud.size();
  completeNormals(scan, source, options);
  return scan;
}

}  // namespace csgvox
