#pragma once
/// Bores found from their walls, and narrow faces from their points. On a raw scan a small bore's or boss's wall
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

/// Parameters of addWallPlanes.
struct WallPlaneOptions {
  std::size_t maxDirections = 6;  ///< directions searched, at most (the heaviest first)
  std::size_t maxPlanes = 32;     ///< planes added, at most
  /// A face's patch links points closer than this many times the median
  /// spacing of the points facing along it (or the detection's cluster
  /// distance, when that is more): as the detection's own patches link the
  /// scan's points (DetectOptions::spacingFactor). On a narrow face only
  /// some normals face along it, so its points lie farther apart than the
  /// scan's (ratio).
  double spacingFactor = 3.0;
};

/// What addWallPlanes found.
struct WallPlaneStats {
  std::size_t directions = 0;  ///< directions and sides searched
  std::size_t tried = 0;       ///< windows with enough points, tested
  std::size_t planes = 0;      ///< planes added
};

/// Adds a plane to `result` for each patch of unassigned points that is a
/// face across a direction of `result`'s surfaces: at least
/// result.minPoints points within 2 epsilon along it whose normals lie
/// within 60 degrees of it, connected, not explained by a surface found and
/// not a plane found (its offset: the points' median). A narrow face (a
/// groove's wall between two wider faces) has its normals blended by the
/// neighbourhoods, and RANSAC's normal test refuses it (InverseCSG 176's
/// scanner scan: its V-grooves' walls, 1 wide, 36-72 % of their points'
/// normals within 60 degrees). The points are assigned to it.
WallPlaneStats addWallPlanes(const PointCloud& cloud, DetectionResult& result,
                             const WallPlaneOptions& options = {});

}  // namespace csgvox
