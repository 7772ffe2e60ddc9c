#pragma once
/// Holes found from their rims. A scanner looks into a small bore at a steep
/// angle and sees few points of its wall, too few for RANSAC; the face around
/// it is seen well and shows the hole as a round gap among its points. Each
/// such gap becomes a hole cylinder, its axis along the face's normal:
/// through the part when the opposite face shows the same gap, down to the
/// face seen at the bottom of the hole (a counterbore's step, a blind hole's
/// floor), or as deep as the wall's own points go. A rectangular gap that the
/// opposite face shows too (a window or a slot through a thin wall, whose
/// sides the scanner sees at a grazing angle) becomes the planes of its four
/// sides, from which the hypotheses build the box that cuts it.

#include <cstddef>

#include "core/point_cloud.h"
#include "primitives/surface_detection.h"

namespace csgvox {

/// Parameters of addRimHoles.
struct RimHoleOptions {
  /// Smallest hole radius, in units of the median spacing of the rim's
  /// points (ratio): a sparse patch of a face has gaps of one or two spacings.
  double minRadiusSpacings = 2.5;
  /// Largest hole radius, fraction of the diagonal D.
  double maxRadius = 0.15;
  /// A gap is round when the nearest points of its 12 angular sectors lie at
  /// distances from its centre that spread by at most this fraction of the
  /// radius (ratio), leaving out the nearest and the farthest sector (a
  /// sparse rim may lack a point near the circle in one). A slot's spread by
  /// its length over its width; a square's by only 15 %: a square hole reads
  /// as a round one.
  double roundness = 0.2;
  /// ... plus this many point spacings of the face (ratio), or
  /// roundnessGaps' share when that is more.
  double roundnessSpacings = 0.5;
  /// ... or this many radii of the typical empty circle around the gap
  /// (the median of the distance map's maxima used by minPeakRatio; ratio):
  /// a scanner's rows lie farther apart than the points along a row (which
  /// the spacing measures), so a rim that crosses the rows is ragged by up
  /// to a row's distance (the scanner scan of InverseCSG part 081: the rims
  /// of its bolt holes, radius 0.16-0.19, ragged by 2.4-2.8 spacings, the
  /// empty circles around them 1.7-1.9 spacings in radius). The points of
  /// the sectors are gathered out to twice the larger of the spacing and
  /// that radius beyond the circle. 0: the spacing alone.
  double roundnessGaps = 1.0;
  /// A gap is a hole only when its radius is at least this many times the
  /// median radius of the empty circles among the face's points around it
  /// (ratio): a scanner's rows leave a regular pattern of gaps wider than
  /// the spacing along a row, and a sparse patch of a face has gaps of
  /// about 1.7 spacings.
  double minPeakRatio = 2.5;
  /// Fewest inliers of a plane searched for gaps (count).
  std::size_t minPlaneInliers = 100;
  /// Also look for rectangular gaps through a wall (windows and slots),
  /// added as the planes of their sides.
  bool windows = true;
};

/// What addRimHoles found.
struct RimHoleStats {
  std::size_t gaps = 0;  ///< round gaps found in the planes
  /// Round rims that a curved surface found already explains, and windows
  /// whose four sides detection found already (count).
  std::size_t explained = 0;
  std::size_t holes = 0;       ///< hole cylinders added
  std::size_t windowGaps = 0;  ///< rectangular gaps found in the planes
  std::size_t windows = 0;     ///< windows through a wall added (as the planes of their sides)
};

/// Adds a hole cylinder (convex false) to `result` for each round gap in a
/// plane's points that no curved surface of `result` explains and whose
/// depth the scan shows (a matching gap in the opposite face, a face at the
/// bottom, or the wall's own points). The new surface's inliers are the rim
/// points of the gap (still assigned to their plane: they give the hole's
/// position and ends), the bottom face's points inside it and the wall points
/// no surface held (those are assigned to it). With `options.windows`, adds
/// the planes of the sides of each rectangular gap matched by the same gap in
/// the opposite face (sides whose plane `result` holds already are not added
/// again); each holds the rims' points along its side and the side's own
/// points no surface held (assigned to it). `result` must be the output of
/// fitSurfaces (its centroids are kept up to date).
RimHoleStats addRimHoles(const PointCloud& cloud, DetectionResult& result,
                         const RimHoleOptions& options = {});

}  // namespace csgvox
