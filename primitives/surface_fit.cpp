// fitSurfaces: fits every surface, reassigns the points, removes
// redundant surfaces, re-fits and sorts.

#include "primitives/surface_fit.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "primitives/surface_fit_internal.h"

namespace csgvox {

namespace {

using namespace surface_fit_detail;

// The simpler type a curved surface has flattened into on a part of
// diagonal D, if any: a plane for a cylinder or sphere too wide to be
// plausible, a cone that is implausible on its flat side or wider than D
// where its points lie; a cylinder for a cone within 2 degrees of one.
// (A part's straight side that RANSAC took as a wide cylinder together with
// a strip of the round next to it fits so once the round's points go to
// the round; a cone fitted to a face's points can run its apex out far
// beyond the part.)
std::optional<SurfaceType> flattenedInto(const Surface& s, double diag, const PointCloud& cloud) {
  if (plausibleSurface(s, diag, cloud, s.inliers)) return std::nullopt;
  switch (s.type()) {
    case SurfaceType::Cylinder:
    case SurfaceType::Sphere:
      return SurfaceType::Plane;
    case SurfaceType::Cone:
      if (plausibleSurface(s, diag) || s.as<ConeSurface>()->halfAngle > 0.25 * std::numbers::pi)
        return SurfaceType::Plane;
      return SurfaceType::Cylinder;
    case SurfaceType::Plane:
    case SurfaceType::Torus:
      return std::nullopt;
  }
  return std::nullopt;
}

// Fits every surface on its inliers (in parallel); surfaces whose fit
// degenerates keep their parameters, and (options.flattenToPlanes) a curved
// surface whose fit has flattened becomes the plane of its inliers.
void fitAll(const PointCloud& cloud, DetectionResult& result, const SurfaceFitOptions& options,
            FitMemo& memo) {
  const FitScales scales = fitScales(result, options);
  const double diag = result.diagonal;
  // One task per surface: the fits differ widely in cost (largest surfaces first).
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, result.surfaces.size(), 1),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t s = range.begin(); s != range.end(); ++s) {
          Surface& surf = result.surfaces[s];
          Surface trial = surf;
          if (fitSurface(cloud, surf.inliers, trial, scales, options, &memo) >= 0.0)
            surf = std::move(trial);
          if (!options.flattenToPlanes || !(diag > 0.0)) continue;
          const std::optional<SurfaceType> into = flattenedInto(surf, diag, cloud);
          if (!into) continue;
          // The simpler surface fitted on the inliers; a cone whose cylinder
          // would be too wide for the part is their plane.
          Surface simpler;
          const auto fits = [&](SurfaceType type) {
            simpler = Surface{};
            return initialSurface(cloud, surf.inliers, type, simpler) &&
                   fitSurface(cloud, surf.inliers, simpler, scales, options, &memo) >= 0.0 &&
                   plausibleSurface(simpler, diag);
          };
          if (!(*into == SurfaceType::Cylinder && fits(SurfaceType::Cylinder)) &&
              !fits(SurfaceType::Plane)) {
            continue;
          }
          simpler.inliers = std::move(surf.inliers);
          surf = std::move(simpler);
        }
      },
      tbb::simple_partitioner());
}

// True for a cylinder, or a cone within kStepConeAngle of one.
constexpr double kStepConeAngle = 5.0 * std::numbers::pi / 180.0;
bool nearCylinder(const Surface& s) {
  if (s.type() == SurfaceType::Cylinder) return true;
  const auto* c = s.as<ConeSurface>();
  return c && c->halfAngle < kStepConeAngle;
}

// The two cylinders a surface's inliers form when they lie at two distinct
// distances from its axis, or nothing. RANSAC takes a hole and its
// counterbore, or a shaft and its shoulder, as one surface when their radii
// differ by less than epsilon; a fit then finds a cylinder or a slight cone
// between the two. The inliers' distances from the axis (found from their
// normals, which the radii do not sway) split at the widest empty band
// between consecutive ones that leaves at least `minPoints` points on either
// side. The split holds when the band is wider than the position noise and
// than kStepGap pooled standard deviations of the two sides (a continuous
// spread of distances, from noise or a cone, leaves bands of about the
// spread over the number of points; a tessellated scan's facets spread each
// side by a few per cent of its radius), the two sides follow each other
// along the axis (their axial spans share at most `overlap`), and the two
// sides fit cylinders with at most half the whole's RMS distance.
constexpr double kStepGap = 1.5;
std::optional<std::pair<Surface, Surface>> steppedCylinders(
    const PointCloud& cloud, const Surface& surf, std::size_t minPoints, double overlap,
    const FitScales& scales, const SurfaceFitOptions& options, FitMemo& memo) {
  const std::size_t n = surf.inliers.size();
  if (!nearCylinder(surf) || n < 2 * minPoints) return std::nullopt;
  const double rms = rmsDistance(cloud, surf.inliers, surf);
  Surface normalsAxis;
  if (!(rms > 0.0) || !initialSurface(cloud, surf.inliers, SurfaceType::Cylinder, normalsAxis))
    return std::nullopt;
  const Vec3 a = normalsAxis.as<CylinderSurface>()->axisPoint;
  const Vec3 d = normalsAxis.as<CylinderSurface>()->axisDir;
  std::vector<std::pair<double, std::uint32_t>> rho(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3 v = cloud.points[surf.inliers[k]] - a;
    rho[k] = {(v - v.dot(d) * d).norm(), surf.inliers[k]};
  }
  std::sort(rho.begin(), rho.end());
  // The widest empty band between consecutive distances that leaves at least
  // minPoints points on either side.
  std::size_t best = 0;
  double empty = 0.0;
  for (std::size_t k = minPoints; k + minPoints <= n; ++k) {
    if (const double g = rho[k].first - rho[k - 1].first; g > empty) empty = g, best = k;
  }
  if (best == 0 || !(empty > scales.position)) return std::nullopt;
  // Each side's spread of distances (pooled) and span along the axis. A
  // step's two radii follow each other along the axis; sides that share
  // their axial span by more than `overlap` are a patch of some other shape
  // (a tessellated arc whose facets lie at two distances from the axis over
  // the same height), not a hole and its counterbore.
  const std::array<std::pair<std::size_t, std::size_t>, 2> sides{{{0, best}, {best, n}}};
  std::array<std::pair<double, double>, 2> span;
  double sse = 0.0;
  for (std::size_t side = 0; side < 2; ++side) {
    const auto [lo, hi] = sides[side];
    double mean = 0.0;
    span[side] = {std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity()};
    for (std::size_t k = lo; k < hi; ++k) {
      mean += rho[k].first;
      const double t = (cloud.points[rho[k].second] - a).dot(d);
      span[side] = {std::min(span[side].first, t), std::max(span[side].second, t)};
    }
    mean /= double(hi - lo);
    for (std::size_t k = lo; k < hi; ++k) sse += (rho[k].first - mean) * (rho[k].first - mean);
  }
  if (!(empty > kStepGap * std::sqrt(sse / double(n)))) return std::nullopt;
  if (std::min(span[0].second, span[1].second) - std::max(span[0].first, span[1].first) > overlap)
    return std::nullopt;
  std::array<Surface, 2> parts;
  double partsSquared = 0.0;
  for (std::size_t side = 0; side < 2; ++side) {
    const auto [lo, hi] = sides[side];
    std::vector<std::uint32_t> indices;
    indices.reserve(hi - lo);
    for (std::size_t k = lo; k < hi; ++k) indices.push_back(rho[k].second);
    std::sort(indices.begin(), indices.end());
    Surface& part = parts[side];
    if (!initialSurface(cloud, indices, SurfaceType::Cylinder, part)) return std::nullopt;
    const double partRms = fitSurface(cloud, indices, part, scales, options, &memo);
    if (!(partRms >= 0.0)) return std::nullopt;
    partsSquared += partRms * partRms * double(indices.size());
    part.inliers = std::move(indices);
    part.rms = partRms;
  }
  if (!(std::sqrt(partsSquared / double(n)) <= 0.5 * rms)) return std::nullopt;
  return std::pair{std::move(parts[0]), std::move(parts[1])};
}

// Replaces every surface whose inliers form two stepped cylinders
// (steppedCylinders) by the two, the inner one first; a part is split again
// if it is itself stepped. The assignment is left to the reassignment and
// the final bookkeeping of fitSurfaces, which rebuild it.
void splitSteps(const PointCloud& cloud, DetectionResult& result, const SurfaceFitOptions& options,
                FitMemo& memo) {
  const FitScales scales = fitScales(result, options);
  const std::size_t minPoints = std::max<std::size_t>(1, result.minPoints);
  std::vector<Surface> pending(std::make_move_iterator(result.surfaces.rbegin()),
                               std::make_move_iterator(result.surfaces.rend()));
  result.surfaces.clear();
  while (!pending.empty()) {
    Surface surf = std::move(pending.back());
    pending.pop_back();
    if (auto parts =
            steppedCylinders(cloud, surf, minPoints, result.epsilon, scales, options, memo)) {
      pending.push_back(std::move(parts->second));
      pending.push_back(std::move(parts->first));
    } else {
      result.surfaces.push_back(std::move(surf));
    }
  }
}

// The scaled squared residual of point i on surface t (removeRedundant's and
// mergeDuplicateSurfaces' measure), or `cap` when the point is not on it.
double explainScore(const PointCloud& cloud, const DetectionResult& result, const Surface& t,
                    std::uint32_t i, const FitScales& scales, double cap) {
  const Vec3& p = cloud.points[i];
  if (surfaceDistance(t, p) > result.epsilon) return cap;
  const PointFit fit = pointFit(t, p, cloud.normals[i], scales);
  if (fit.cosine < result.normalThreshold || (scales.normal > 0.0 && fit.normal2 > kNormalChi2)) {
    return cap;
  }
  return std::pow(fit.distance / scales.position, 2) + fit.normal2;
}

// The centroid of every surface's inliers, and the assignment from them.
void indexInliers(const PointCloud& cloud, DetectionResult& result) {
  result.centroids.assign(result.surfaces.size(), Vec3::Zero());
  std::fill(result.assignment.begin(), result.assignment.end(), -1);
  for (std::size_t s = 0; s < result.surfaces.size(); ++s) {
    const Surface& surf = result.surfaces[s];
    Vec3 sum = Vec3::Zero();
    for (std::uint32_t i : surf.inliers) {
      sum += cloud.points[i];
      result.assignment[i] = int(s);
    }
    if (!surf.inliers.empty()) result.centroids[s] = sum / double(surf.inliers.size());
  }
}

// Removes surfaces whose inliers other surfaces explain: a duplicate, a
// plane strip cut from a large cylinder, or one flexible surface (a torus,
// a sphere) spanning several true ones once those are found. Of the
// redundant surfaces, the one the others fit best relative to itself goes
// first (ties: the more complex type), then the test is repeated.
void removeRedundant(const PointCloud& cloud, DetectionResult& result,
                     const SurfaceFitOptions& options) {
  std::vector<Surface>& surfaces = result.surfaces;
  const double eps = result.epsilon;
  std::vector<char> alive(surfaces.size(), 1);
  const FitScales scales = fitScales(result, options);
  const double cap = std::pow(eps / scales.position, 2) + kNormalChi2;
  const auto score = [&](std::size_t t, std::uint32_t i) {
    return explainScore(cloud, result, surfaces[t], i, scales, cap);
  };
  // The scores of every inlier on its own surface and on every other surface
  // that explains it (below the cap), computed once in parallel over the
  // points; the surfaces do not change below, so each round only looks them up.
  std::vector<std::size_t> first(surfaces.size() + 1, 0);
  for (std::size_t s = 0; s < surfaces.size(); ++s)
    first[s + 1] = first[s] + surfaces[s].inliers.size();
  std::vector<std::uint32_t> owner(first.back());
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    std::fill(owner.begin() + std::ptrdiff_t(first[s]),
              owner.begin() + std::ptrdiff_t(first[s + 1]), std::uint32_t(s));
  }
  using Entry = std::pair<std::uint32_t, double>;  // surface, score
  std::vector<std::vector<Entry>> near(first.back());
  tbb::parallel_for(std::size_t(0), first.back(), [&](std::size_t k) {
    const std::uint32_t i = surfaces[owner[k]].inliers[k - first[owner[k]]];
    for (std::size_t t = 0; t < surfaces.size(); ++t) {
      const double v = score(t, i);
      if (v < cap || t == owner[k]) near[k].emplace_back(std::uint32_t(t), v);
    }
  });
  while (true) {
    std::vector<double> excess(surfaces.size(), -1e300);
    tbb::parallel_for(std::size_t(0), surfaces.size(), [&](std::size_t s) {
      if (!alive[s] || surfaces[s].inliers.empty()) return;
      std::size_t explained = 0;
      double sum = 0.0;
      for (std::size_t k = first[s]; k < first[s + 1]; ++k) {
        double self = cap, other = cap;
        for (const auto& [t, v] : near[k]) {
          if (t == s) {
            self = v;
          } else if (alive[t]) {
            other = std::min(other, v);
          }
        }  // surfaces missing from near[k] score the cap
        explained += other < cap;
        sum += self - other;
      }
      // Redundant: others explain most of its points, and about as well.
      const double mean = sum / double(surfaces[s].inliers.size());
      if (double(explained) >= options.redundantFraction * double(surfaces[s].inliers.size()) &&
          mean >= -0.5) {
        excess[s] = mean;
      }
    });
    int worst = -1;
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      if (excess[s] <= -1e299) continue;
      if (worst < 0) {
        worst = int(s);
        continue;
      }
      const std::size_t w = std::size_t(worst);
      const double tie = 0.25;  // in units of the scaled squared residual
      const bool better =
          excess[s] > excess[w] + tie ||
          (excess[s] > excess[w] - tie &&
           (parameterCount(surfaces[s].type()) > parameterCount(surfaces[w].type()) ||
            (parameterCount(surfaces[s].type()) == parameterCount(surfaces[w].type()) &&
             surfaces[s].inliers.size() < surfaces[w].inliers.size())));
      if (better) worst = int(s);
    }
    if (worst < 0) break;
    alive[std::size_t(worst)] = 0;
  }
  std::vector<Surface> kept;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    if (alive[s]) kept.push_back(std::move(surfaces[s]));
  }
  surfaces = std::move(kept);
}

// Sorts surfaces by inlier count (largest first, stable) and renumbers the assignment.
void sortBySize(DetectionResult& result) {
  const std::size_t n = result.surfaces.size();
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return result.surfaces[x].inliers.size() > result.surfaces[y].inliers.size();
  });
  std::vector<int> newIndex(n);
  std::vector<Surface> surfaces;
  std::vector<Vec3> centroids;
  for (std::size_t k = 0; k < n; ++k) {
    newIndex[order[k]] = int(k);
    surfaces.push_back(std::move(result.surfaces[order[k]]));
    if (result.centroids.size() == n) centroids.push_back(result.centroids[order[k]]);
  }
  for (int& s : result.assignment) {
    if (s >= 0) s = newIndex[std::size_t(s)];
  }
  result.surfaces = std::move(surfaces);
  if (centroids.size() == n) result.centroids = std::move(centroids);
}

}  // namespace

std::size_t mergeDuplicateSurfaces(const PointCloud& cloud, DetectionResult& result,
                                   const SurfaceFitOptions& options) {
  if (result.assignment.size() != cloud.size()) {
    throw std::invalid_argument(
        "mergeDuplicateSurfaces: the detection result belongs to another cloud");
  }
  std::vector<Surface>& surfaces = result.surfaces;
  if (surfaces.size() < 2) return 0;
  if (!cloud.hasNormals()) {
    throw std::invalid_argument("mergeDuplicateSurfaces needs one normal per point");
  }
  // By distance and the cosine threshold alone: the fits at a bore's mouth
  // take the normals of the blended edge, which the normal noise measured
  // inside the faces would call a tilt.
  FitScales scales = fitScales(result, options);
  scales.normal = 0.0;
  const double cap = std::pow(result.epsilon / scales.position, 2) + kNormalChi2;
  // Smallest first: a surface goes into the one of its type and convexity
  // that explains most of its points (the larger on a tie), when that one
  // explains them about as well as it does.
  std::vector<std::size_t> order(surfaces.size());
  for (std::size_t s = 0; s < order.size(); ++s) order[s] = s;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return surfaces[a].inliers.size() < surfaces[b].inliers.size();
  });
  std::vector<char> alive(surfaces.size(), 1);
  std::vector<double> self;
  std::size_t merged = 0;
  for (std::size_t b : order) {
    Surface& from = surfaces[b];
    if (from.type() == SurfaceType::Plane || from.inliers.empty()) continue;
    self.clear();
    for (std::uint32_t i : from.inliers) {
      self.push_back(explainScore(cloud, result, from, i, scales, cap));
    }
    const double n = double(from.inliers.size());
    std::size_t into = surfaces.size(), bestExplained = 0;
    for (std::size_t a = 0; a < surfaces.size(); ++a) {
      const Surface& to = surfaces[a];
      if (a == b || !alive[a] || to.type() != from.type() || to.convex != from.convex) continue;
      std::size_t explained = 0;
      double sum = 0.0;
      for (std::size_t k = 0; k < from.inliers.size(); ++k) {
        const double other = explainScore(cloud, result, to, from.inliers[k], scales, cap);
        explained += other < cap;
        sum += self[k] - other;
      }
      if (double(explained) < options.redundantFraction * n || sum / n < -0.5) continue;
      if (explained > bestExplained ||
          (explained == bestExplained && to.inliers.size() > surfaces[into].inliers.size())) {
        into = a;
        bestExplained = explained;
      }
    }
    if (into == surfaces.size()) continue;
    Surface& to = surfaces[into];
    to.inliers.insert(to.inliers.end(), from.inliers.begin(), from.inliers.end());
    std::sort(to.inliers.begin(), to.inliers.end());
    to.rms = rmsDistance(cloud, to.inliers, to);
    from.inliers.clear();
    alive[b] = 0;
    ++merged;
  }
  if (merged == 0) return 0;
  std::vector<Surface> kept;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    if (alive[s]) kept.push_back(std::move(surfaces[s]));
  }
  surfaces = std::move(kept);
  indexInliers(cloud, result);
  sortBySize(result);
  return merged;
}

void fitSurfaces(const PointCloud& cloud, DetectionResult& result, const SurfaceFitOptions& options,
                 FitMemo* memo) {
  if (result.assignment.size() != cloud.size()) {
    throw std::invalid_argument("fitSurfaces: the detection result belongs to another cloud");
  }
  if (result.surfaces.empty()) return;
  if (!cloud.hasNormals()) throw std::invalid_argument("fitSurfaces needs one normal per point");
  if (!(result.epsilon > 0.0)) {
    throw std::invalid_argument("fitSurfaces: the detection result has no epsilon");
  }
  if (memo != nullptr && &memo->cloud() != &cloud) {
    throw std::invalid_argument("fitSurfaces: the memo belongs to another cloud");
  }
  std::optional<FitMemo> own;
  FitMemo& fits = memo != nullptr ? *memo : own.emplace(cloud);
  fitAll(cloud, result, options, fits);
  if (options.removeRedundant) removeRedundant(cloud, result, options);
  if (options.splitSteps) splitSteps(cloud, result, options, fits);
  if (options.reassign) {
    reassignPoints(cloud, result, std::max<std::size_t>(1, result.minPoints),
                   options.connectedPatches, options.normalNoiseTest);
    fitAll(cloud, result, options, fits);
  }
  // Final bookkeeping: rms, centroids and the assignment on the final inliers.
  for (Surface& surf : result.surfaces) surf.rms = rmsDistance(cloud, surf.inliers, surf);
  indexInliers(cloud, result);
  sortBySize(result);
  if (result.surfaces.empty() && result.status == DetectionResult::Status::Ok) {
    result.status = DetectionResult::Status::NoSurfaces;
    result.message = "no surface kept enough points after the surface fit";
  }
}

}  // namespace csgvox
