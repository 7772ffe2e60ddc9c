#include "mesh/fit_metrics.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/nearest_neighbors.h"
#include "mesh/surface_sampler.h"

namespace csgvox {
namespace {

// Distance from p to the surface sampled by (points, normals): over the few
// nearest samples, the distance to each sample's tangent plane, growing into
// the point distance once p projects more than one spacing away from the
// sample. Exact on smooth regions; off by at most about a spacing near edges.
// `nearestOut` receives the sample that gave the distance (whose tangent
// plane holds p), so its normal is the surface normal seen from p.
// `near` holds the previous query's samples (they bound this search) and
// receives this one's.
double surfaceDistance(const Vec3& p, const NearestNeighbors& index, const std::vector<Vec3>& pts,
                       const std::vector<Vec3>& normals, double spacing,
                       std::vector<std::uint32_t>& near, std::uint32_t* nearestOut) {
  const std::size_t k = normals.empty() ? 1 : 4;
  index.kNearestWithin(p, k, kNearestBound(pts, p, near, k), near);
  if (nearestOut) *nearestOut = near.front();
  if (normals.empty()) return (p - pts[near.front()]).norm();
  double best = std::numeric_limits<double>::infinity();
  for (std::uint32_t i : near) {
    const Vec3 v = p - pts[i];
    const double along = normals[i].dot(v);
    const double lateral = std::max(0.0, (v - along * normals[i]).norm() - spacing);
    const double d = std::sqrt(along * along + lateral * lateral);
    if (d < best) {
      best = d;
      if (nearestOut) *nearestOut = i;
    }
  }
  return best;
}

}  // namespace

FitMetrics evaluateFit(const CsgTree& tree, const PointCloud& scan, const FitOptions& options) {
  if (scan.empty()) throw std::invalid_argument("the scan has no points");
  FitMetrics m;
  m.points = scan.size();
  m.diagonal = scan.diagonal();
  m.hasNormals = scan.hasNormals();

  SampleOptions so;
  so.points = options.surfaceSamples;
  so.seed = options.seed;
  const SurfaceSample surface = sampleSurface(tree, so);
  m.surfaceArea = surface.surfaceArea;
  const std::vector<Vec3>& sp = surface.cloud.points;
  const std::vector<Vec3>& sn = surface.cloud.normals;
  const double surfaceSpacing = std::sqrt(surface.surfaceArea / double(sp.size()));
  const NearestNeighbors surfaceIndex(sp);
  const std::vector<const Node*> leaves = tree.leaves();

  const NearestNeighbors scanIndex(scan.points);

  // Both loops visit their points in space order (cache-friendly queries).
  const std::size_t n = scan.size();
  std::vector<double> eq9(n), dist(n), cosine(n, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& range) {
    std::vector<std::uint32_t> near;
    for (std::size_t at = range.begin(); at != range.end(); ++at) {
      const std::size_t k = scanIndex.order()[at];
      const Vec3& p = scan.points[k];
      double best = std::numeric_limits<double>::infinity();
      for (const Node* leaf : leaves) best = std::min(best, std::abs(leaf->primitive.value(p)));
      eq9[k] = best;
      std::uint32_t nearest = 0;
      dist[k] = surfaceDistance(p, surfaceIndex, sp, sn, surfaceSpacing, near, &nearest);
      if (m.hasNormals) cosine[k] = scan.normals[k].dot(sn[nearest]);
    }
  });

  // Boundary samples to the scan, for the other half of the Chamfer distance.
  const double scanSpacing = std::sqrt(surface.surfaceArea / double(n));
  std::vector<double> back(sp.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sp.size()), [&](const auto& range) {
    std::vector<std::uint32_t> near;
    for (std::size_t at = range.begin(); at != range.end(); ++at) {
      const std::size_t k = surfaceIndex.order()[at];
      back[k] =
          surfaceDistance(sp[k], scanIndex, scan.points, scan.normals, scanSpacing, near, nullptr);
    }
  });

  const double tol = options.withinTolerance * m.diagonal;
  const double cos10 = std::cos(10.0 * std::numbers::pi / 180.0);
  double sumEq9 = 0, sumD2 = 0, sumD = 0, sumCos = 0, sumBack = 0;
  std::size_t within = 0, aligned = 0;
  for (std::size_t k = 0; k < n; ++k) {
    sumEq9 += eq9[k] * eq9[k];
    sumD2 += dist[k] * dist[k];
    sumD += dist[k];
    m.maxDistance = std::max(m.maxDistance, dist[k]);
    within += dist[k] <= tol;
    sumCos += cosine[k];
    aligned += cosine[k] >= cos10;
  }
  for (double b : back) sumBack += b;
  m.rmse = std::sqrt(sumEq9 / double(n));
  m.surfaceRmse = std::sqrt(sumD2 / double(n));
  m.meanDistance = sumD / double(n);
  m.chamfer = 0.5 * (m.meanDistance + sumBack / double(sp.size()));
  m.withinFraction = double(within) / double(n);
  if (m.hasNormals) {
    m.normalAgreement = sumCos / double(n);
    m.normalsWithin10Deg = double(aligned) / double(n);
  }
  return m;
}

}  // namespace csgvox
