#include "primitives/outlier_removal.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "core/nearest_neighbors.h"
#include "core/principal_axes.h"
#include "core/statistics.h"

namespace csgvox {
namespace {

// Scale of the median absolute deviation to a normal deviation.
constexpr double kMadToSigma = 1.4826;

/// Per point: the mean distance to its k nearest neighbours (itself
/// excluded), its distance to the plane of those neighbours, and their RMS
/// distance to that plane; the neighbours themselves.
struct Local {
  unsigned k = 0;
  std::vector<std::uint32_t> hood;  ///< k per point
  std::vector<double> spacing;
  std::vector<double> offPlane;
  std::vector<double> planeRms;
};

Local localMeasures(std::span<const Vec3> points, unsigned k) {
  const std::size_t n = points.size();
  const NearestNeighbors tree(points);
  Local local;
  local.k = k;
  local.hood.resize(n * k);
  local.spacing.resize(n);
  local.offPlane.resize(n);
  local.planeRms.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& range) {
    std::vector<std::uint32_t> found, previous;
    std::vector<double> d2;
    for (std::size_t at = range.begin(); at != range.end(); ++at) {
      const std::size_t i = tree.order()[at];  // neighbours visited together: cache-friendly
      // The previous point's neighbours bound the search (the same result).
      tree.kNearestWithin(points[i], k + 1, kNearestBound(points, points[i], previous, k + 1),
                          found, &d2);
      previous = found;
      // The point itself (or a copy of it) comes first; drop the entry of i.
      auto self = std::find(found.begin(), found.end(), std::uint32_t(i));
      if (self != found.end()) {
        d2.erase(d2.begin() + (self - found.begin()));
        found.erase(self);
      } else {
        found.pop_back();
        d2.pop_back();
      }
      double sum = 0.0;
      for (double d : d2) sum += std::sqrt(d);
      local.spacing[i] = sum / k;
      std::copy(found.begin(), found.end(), local.hood.begin() + std::ptrdiff_t(i * k));
      const PrincipalAxes axes = principalAxes(points, found);
      local.offPlane[i] = std::abs(axes.leastAxis().dot(points[i] - axes.mean));
      local.planeRms[i] = std::sqrt(std::max(0.0, axes.variances[2]));
    }
  });
  return local;
}

}  // namespace

Outliers findOutliers(std::span<const Vec3> points, const OutlierOptions& options) {
  if (options.neighbors < 4) {
    throw std::invalid_argument("findOutliers: neighbors must be at least 4");
  }
  const std::size_t n = points.size();
  Outliers result;
  result.outlier.assign(n, false);
  const auto k = static_cast<unsigned>(options.neighbors);
  if (n <= k) return result;
  const Local local = localMeasures(points, k);
  result.noise = median(local.planeRms);
  result.spacing = median(local.spacing);

  // Scattered: spacing against the neighbours' spacing, on a log scale.
  std::vector<double> ratio(n), typical(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    std::vector<double> around(k);
    for (unsigned l = 0; l < k; ++l) around[l] = local.spacing[local.hood[i * k + l]];
    typical[i] = median(std::move(around));
    ratio[i] = typical[i] > 0.0 ? std::log(local.spacing[i] / typical[i]) : 0.0;
  });
  const double centre = median(ratio);
  std::vector<double> deviation(n);
  for (std::size_t i = 0; i < n; ++i) deviation[i] = std::abs(ratio[i] - centre);
  const double spread = kMadToSigma * median(std::move(deviation));
  const double scatteredAbove =
      std::max(std::log(options.spacingRatio), centre + options.robustSpread * spread);
  const double farAbove = options.globalRatio * result.spacing;

  // Off the surface: distance to the neighbours' plane against their noise.
  const double noise = result.noise;
  for (std::size_t i = 0; i < n; ++i) {
    if (ratio[i] > scatteredAbove || local.spacing[i] > farAbove) {
      result.outlier[i] = true;
      ++result.scattered;
      continue;
    }
    const double limit =
        std::max({options.offPlaneFactor * local.planeRms[i], options.offPlaneFactor * noise,
                  options.offSpacing * typical[i]});
    if (local.offPlane[i] > limit && ratio[i] > std::log(options.offRatio)) {
      result.outlier[i] = true;
      ++result.offSurface;
    }
  }
  return result;
}

}  // namespace csgvox
