// Point reassignment: every point goes to the surface that explains it best,
// with surfaces' points kept in connected patches.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include "primitives/surface_fit.h"
#include "primitives/surface_fit_internal.h"

namespace csgvox {

namespace {

using namespace surface_fit_detail;

// Points binned into cubic cells of a given side. Two cells are adjacent
// when they touch (26-neighbourhood): the 3D analogue of the bitmap on which
// RANSAC (Schnabel et al. 2007, CGAL's cluster epsilon) decides that the
// points of a shape form one connected patch.
class CellGrid {
 public:
  using Key = std::array<std::int64_t, 3>;

  CellGrid(const PointCloud& cloud, std::span<const std::uint32_t> indices, double side)
      : side_(side) {
    for (std::uint32_t i : indices) cells_[keyOf(cloud.points[i])].push_back(i);
  }

  Key keyOf(const Vec3& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() / side_)),
            static_cast<std::int64_t>(std::floor(p.y() / side_)),
            static_cast<std::int64_t>(std::floor(p.z() / side_))};
  }

  // Calls visit(key, points) for the occupied cells adjacent to (or equal to) the cell k.
  template <class Visit>
  void forAdjacent(const Key& k, Visit&& visit) const {
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(Key{k[0] + dx, k[1] + dy, k[2] + dz});
          if (it != cells_.end()) visit(it->first, it->second);
        }
      }
    }
  }

  // True when the cell of p is occupied or adjacent to an occupied one.
  bool touches(const Vec3& p) const {
    bool any = false;
    forAdjacent(keyOf(p), [&](const Key&, const std::vector<std::uint32_t>&) { any = true; });
    return any;
  }

  // Marks in `isolated` the points of the connected groups of cells holding
  // fewer than `minPoints` points, when another group holds at least that many.
  void markSmallGroups(std::size_t minPoints, std::vector<char>& isolated) const {
    std::unordered_map<Key, std::size_t, KeyHash> slot;
    std::vector<const Key*> keys;
    std::vector<const std::vector<std::uint32_t>*> points;
    for (const auto& [key, pts] : cells_) {
      slot.emplace(key, keys.size());
      keys.push_back(&key);
      points.push_back(&pts);
    }
    std::vector<std::size_t> parent(keys.size());
    for (std::size_t c = 0; c < keys.size(); ++c) parent[c] = c;
    const auto root = [&](std::size_t c) {
      while (parent[c] != c) c = parent[c] = parent[parent[c]];
      return c;
    };
    for (std::size_t c = 0; c < keys.size(); ++c) {
      forAdjacent(*keys[c], [&](const Key& other, const std::vector<std::uint32_t>&) {
        const std::size_t x = root(c), y = root(slot.at(other));
        if (x != y) parent[std::max(x, y)] = std::min(x, y);
      });
    }
    std::vector<std::size_t> size(keys.size(), 0);
    for (std::size_t c = 0; c < keys.size(); ++c) size[root(c)] += points[c]->size();
    // Without a patch of that size there is nothing to be apart from: the
    // surface stands or falls by its count alone.
    if (keys.empty() || *std::max_element(size.begin(), size.end()) < minPoints) return;
    for (std::size_t c = 0; c < keys.size(); ++c) {
      if (size[root(c)] >= minPoints) continue;
      for (std::uint32_t i : *points[c]) isolated[i] = 1;
    }
  }

 private:
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::size_t h = 1469598103934665603ull;
      for (std::int64_t v : k) h = (h ^ static_cast<std::size_t>(v)) * 1099511628211ull;
      return h;
    }
  };
  double side_;
  std::unordered_map<Key, std::vector<std::uint32_t>, KeyHash> cells_;
};

}  // namespace

void reassignPoints(const PointCloud& cloud, DetectionResult& result, std::size_t minPoints,
                    bool connectedPatches, bool normalNoiseTest) {
  const double eps = result.epsilon;
  const double cell = result.clusterEpsilon;
  const FitScales scales = fitScales(result);
  const double threshold = result.normalThreshold;
  std::vector<Surface>& surfaces = result.surfaces;
  std::vector<char> alive(surfaces.size(), 1);
  result.assignment.assign(cloud.size(), -1);
  // The surface point i fits best among the live ones that `allowed` accepts, or -1;
  // with `noiseTest`, its normal must also lie within the normal noise.
  const auto bestSurface = [&](std::size_t i, const auto& allowed, bool noiseTest = true) {
    const Vec3& p = cloud.points[i];
    int best = -1;
    double bestScore = std::numeric_limits<double>::infinity();
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      if (!alive[s] || surfaceDistance(surfaces[s], p) > eps || !allowed(s)) continue;
      const PointFit fit = pointFit(surfaces[s], p, cloud.normals[i], scales);
      if (fit.cosine < threshold || (noiseTest && scales.normal > 0.0 && fit.normal2 > kNormalChi2))
        continue;
      const double score = std::pow(fit.distance / scales.position, 2) + fit.normal2;
      if (score < bestScore) {
        best = int(s);
        bestScore = score;
      }
    }
    return best;
  };
  for (int round = 0; round < 8; ++round) {
    tbb::parallel_for(std::size_t(0), cloud.size(), [&](std::size_t i) {
      result.assignment[i] = bestSurface(i, [](std::size_t) { return true; });
    });
    // The distance test alone also accepts the noise tails of neighbouring
    // surfaces that reach into this surface's band far from its patch (the
    // outer points of a coaxial cylinder of a slightly smaller radius, all
    // along it). Detection accepted a surface only as a connected patch of
    // at least minPoints points (cluster epsilon apart); points that form
    // smaller components of a surface are not on its patch, and go to the
    // best surface whose patch they touch, if any.
    if (connectedPatches && cell > 0.0) {
      std::vector<std::vector<std::uint32_t>> members(surfaces.size());
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (result.assignment[i] >= 0) {
          members[std::size_t(result.assignment[i])].push_back(std::uint32_t(i));
        }
      }
      std::vector<char> isolated(cloud.size(), 0);
      tbb::parallel_for(std::size_t(0), surfaces.size(), [&](std::size_t s) {
        CellGrid(cloud, members[s], cell).markSmallGroups(minPoints, isolated);
      });
      std::vector<std::uint32_t> moved;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (isolated[i]) moved.push_back(std::uint32_t(i));
      }
      if (!moved.empty()) {
        std::vector<std::vector<std::uint32_t>> kept(surfaces.size());
        for (std::size_t s = 0; s < surfaces.size(); ++s) {
          std::copy_if(members[s].begin(), members[s].end(), std::back_inserter(kept[s]),
                       [&](std::uint32_t i) { return !isolated[i]; });
        }
        std::vector<CellGrid> grids;
        grids.reserve(surfaces.size());
        for (std::size_t s = 0; s < surfaces.size(); ++s) {
          grids.emplace_back(cloud, kept[s], cell);
        }
        tbb::parallel_for(std::size_t(0), moved.size(), [&](std::size_t k) {
          const std::uint32_t i = moved[k];
          const int from = result.assignment[i];
          result.assignment[i] = bestSurface(i, [&](std::size_t s) {
            return int(s) != from && grids[s].touches(cloud.points[i]);
          });
        });
      }
    }
    std::vector<std::size_t> counts(surfaces.size(), 0);
    for (int s : result.assignment) {
      if (s >= 0) ++counts[std::size_t(s)];
    }
    bool dropped = false;
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      if (alive[s] && counts[s] < minPoints) {
        alive[s] = 0;
        dropped = true;
      }
    }
    if (!dropped) break;
  }
  // Without the normal noise test, the points left over go to the surfaces
  // that live by it, by distance and the cosine threshold alone: a strip of
  // blended normals along an edge that RANSAC took for a surface of its own
  // does not live on them.
  if (!normalNoiseTest && scales.normal > 0.0) {
    tbb::parallel_for(std::size_t(0), cloud.size(), [&](std::size_t i) {
      if (result.assignment[i] < 0) {
        result.assignment[i] = bestSurface(
            i, [](std::size_t) { return true; }, false);
      }
    });
  }
  // Compact: keep the live surfaces in order.
  std::vector<int> newIndex(surfaces.size(), -1);
  std::vector<Surface> kept;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    if (!alive[s]) continue;
    newIndex[s] = int(kept.size());
    kept.push_back(std::move(surfaces[s]));
    kept.back().inliers.clear();
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    int& s = result.assignment[i];
    if (s >= 0) s = newIndex[std::size_t(s)];
    if (s >= 0) kept[std::size_t(s)].inliers.push_back(std::uint32_t(i));
  }
  surfaces = std::move(kept);
  result.centroids.assign(surfaces.size(), Vec3::Zero());
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    Surface& surf = surfaces[s];
    Vec3 sum = Vec3::Zero();
    for (std::uint32_t i : surf.inliers) sum += cloud.points[i];
    if (!surf.inliers.empty()) result.centroids[s] = sum / double(surf.inliers.size());
    surf.rms = rmsDistance(cloud, surf.inliers, surf);
  }
}

}  // namespace csgvox
