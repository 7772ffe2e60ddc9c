#include "io/point_arrays.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

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

/// Removes the outliers of a point cloud (with their normals) and counts them.
void removeOutliers(Scan& scan) {
  const Outliers outliers = findOutliers(scan.cloud.points);
  if (outliers.count() == 0) return;
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

}  // namespace

void completeNormals(Scan& scan, const std::string& source, const ReadOptions& options) {
  if (scan.info.fromMesh) return;
  if (options.removeOutliers) removeOutliers(scan);
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
