#include "primitives/thin_features.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>

#include "core/nearest_neighbors.h"

namespace csgvox {

std::string_view thinKindName(ThinKind kind) {
  switch (kind) {
    case ThinKind::Wall:
      return "wall";
    case ThinKind::Slot:
      return "slot";
    case ThinKind::Rod:
      return "rod";
    case ThinKind::Hole:
      return "hole";
  }
  return "?";
}

std::vector<ThinFeature> findThinFeatures(const PointCloud& scan, std::span<const Surface> surfaces,
                                          const ThinFeatureOptions& options) {
  if (!(options.maxThickness > 0.0)) throw std::invalid_argument("maxThickness must be > 0");
  if (!(options.reach > 0.0)) throw std::invalid_argument("reach must be > 0");
  std::vector<ThinFeature> out;
  std::vector<int> planes;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    const Surface& surface = surfaces[s];
    if (surface.inliers.size() < options.minInliers) continue;
    if (surface.as<PlaneSurface>()) {
      planes.push_back(int(s));
    } else if (const auto* c = surface.as<CylinderSurface>()) {
      if (2.0 * c->radius < options.maxThickness) {
        out.push_back({surface.convex ? ThinKind::Rod : ThinKind::Hole, 2.0 * c->radius, int(s)});
      }
    }
  }

  // Each plane's inliers, sampled evenly once; a k-d tree over all of them
  // (built only for planes that have an opposite one near enough).
  std::vector<std::vector<Vec3>> samples(surfaces.size());
  for (int s : planes) {
    const std::vector<std::uint32_t>& inliers = surfaces[std::size_t(s)].inliers;
    const std::size_t n = inliers.size(), k = std::min(n, options.samples);
    for (std::size_t i = 0; i < k; ++i) {
      samples[std::size_t(s)].push_back(scan.points[inliers[i * n / k]]);
    }
  }
  std::vector<std::unique_ptr<NearestNeighbors>> trees(surfaces.size());
  const auto tree = [&](int s) -> const NearestNeighbors& {
    if (!trees[std::size_t(s)]) {
      std::vector<Vec3> points;
      for (std::uint32_t i : surfaces[std::size_t(s)].inliers) points.push_back(scan.points[i]);
      trees[std::size_t(s)] = std::make_unique<NearestNeighbors>(points);
    }
    return *trees[std::size_t(s)];
  };
  const double cosLimit = std::cos(options.parallelAngle * std::numbers::pi / 180.0);
  for (std::size_t i = 0; i < planes.size(); ++i) {
    for (std::size_t j = i + 1; j < planes.size(); ++j) {
      int a = planes[i], b = planes[j];
      const auto& pa = *surfaces[std::size_t(a)].as<PlaneSurface>();
      const auto& pb = *surfaces[std::size_t(b)].as<PlaneSurface>();
      if (pa.normal.dot(pb.normal) > -cosLimit) continue;
      // Sample the plane with fewer inliers; measure against the other.
      if (surfaces[std::size_t(a)].inliers.size() > surfaces[std::size_t(b)].inliers.size()) {
        std::swap(a, b);
      }
      const auto& onto = *surfaces[std::size_t(b)].as<PlaneSurface>();
      const std::vector<Vec3>& points = samples[std::size_t(a)];
      std::size_t facing = 0;
      double sum = 0.0;  // signed distances of the facing points to the other plane
      for (const Vec3& p : points) {
        const double s = onto.normal.dot(p) - onto.offset;
        if (std::abs(s) >= options.maxThickness) continue;  // (no k-d tree for far planes)
        const Vec3 q = p - s * onto.normal;
        double d2 = 0.0;
        tree(b).nearest(q, &d2);
        if (d2 <= options.reach * options.reach) {
          ++facing;
          sum += s;
        }
      }
      if (facing == 0 || double(facing) < options.overlap * double(points.size())) continue;
      const double mean = sum / double(facing);
      // Behind the other plane (s < 0): material between the two, a wall.
      out.push_back({mean < 0.0 ? ThinKind::Wall : ThinKind::Slot, std::abs(mean), a, b});
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const ThinFeature& x, const ThinFeature& y) {
    return x.thickness < y.thickness;
  });
  return out;
}

}  // namespace csgvox
