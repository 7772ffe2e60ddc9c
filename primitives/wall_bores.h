#pragma once
/// Bores found from their walls. On a raw scan a small bore's or boss's wall
/// holds a few dozen points, about RANSAC's least support, and the randomised
/// search often overlooks it (of a housing's eight counterbores and bolt
/// holes, two found; of a flange's six bolt holes, two or three), although
/// the points are there and their normals right. The points no surface took
/// are searched again, along the directions the part already shows (the
/// normals of its planes, the axes of its cylinders, cones and tori): those
/// whose normals lie across one direction are projected onto the plane
/// across it, where a bore's wall is an arc of a circle whose normals all
/// point to its centre (a hole) or away from it (a boss), and each such arc,
/// wide enough and with no points inside the bore between its ends, becomes
/// a cylinder along that direction.

#include <cstddef>
#include <cstdint>

#include "core/point_cloud.h"
#include "primitives/surface_detection.h"

namespace csgvox {

/// Parameters of addWallBores.
struct WallBoreOptions {
  /// Largest radius, fraction of the diagonal D.
  double maxRadius = 0.15;
  /// Smallest radius, in inlier distances (epsilon) (ratio).
  double minRadiusEpsilons = 2.0;
  /// Smallest angle the wall's points cover around the axis without a wide
  /// gap, in radians (60 degrees): a scanner sees a small bore's wall from
  /// the side its views look into; a shorter arc is as well a piece of a
  /// wider round or two strips of parallel faces.
  double minArc = 1.0471975511965976;
  /// Directions searched, at most (the heaviest first).
  std::size_t maxDirections = 6;
  /// Bores added, at most.
  std::size_t maxBores = 64;
  /// Random seed of the pairs of points tried; the same seed, the same bores.
  std::uint64_t seed = 1;
};

/// What addWallBores found.
struct WallBoreStats {
  std::size_t directions = 0;  ///< directions searched
  std::size_t tried = 0;       ///< arcs with enough points, tested
  std::size_t bores = 0;       ///< cylinders added (holes and bosses)
};

/// Adds a cylinder to `result` for each arc of unassigned points that is the
/// wall of a bore (convex false) or a boss (convex true) along a direction
/// of `result`'s surfaces: at least result.minPoints points within epsilon of
/// the circle, normals within the detection's normal threshold of the
/// radial direction and all on the same side, covering options.minArc
/// around the axis, connected along it, no duplicate of a cylinder found,
/// and no more points strictly inside between its ends than a tenth of its
/// own. The wall points are assigned to it. `result` must be the output of
/// fitSurfaces (its centroids are kept up to date).
WallBoreStats addWallBores(const PointCloud& cloud, DetectionResult& result,
                           const WallBoreOptions& options = {});

}  // namespace csgvox
