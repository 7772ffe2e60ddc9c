#pragma once
/// Regularisation of detected surfaces (what GlobFit gives Wu et al.): plane
/// normals and axes that are nearly parallel or orthogonal become exactly so,
/// coplanar planes merge, nearly coaxial axes become one axis, nearly equal
/// radii become equal. The frames come from the data, never from the world
/// axes, so a rotated part is regularised like an aligned one.

#include <numbers>
#include <string>

#include "primitives/surface_detection.h"

namespace csgvox {

/// Options of regularizeSurfaces.
struct RegularizeOptions {
  double angleTolerance =
      3.0 * std::numbers::pi /
      180.0;  ///< directions this close to parallel or orthogonal are snapped, radians
  double offsetTolerance = 1.0;  ///< parallel planes whose offsets differ by at most this merge, in
                                 ///< units of the detection epsilon
  double axisTolerance = 1.0;  ///< parallel axes whose lines are at most this far apart become one,
                               ///< in units of the detection epsilon
  double radiusTolerance =
      1.0;  ///< upper bound on the radius difference made equal, in units of the detection epsilon
            ///< (the bound used is three standard errors of the two fits, at least 0.1 % of D)
  bool orthogonal = true;  ///< snap near-orthogonal directions (planes, axes) to exactly orthogonal
  bool mergeCoplanar = true;  ///< merge coplanar planes of the same orientation into one surface
  bool coaxial =
      true;  ///< snap nearly coaxial cylinders, cones and tori (and sphere centres) to one axis
  bool equalRadii = true;  ///< make nearly equal radii (and cone angles) equal; merge surfaces that
                           ///< become identical
};

/// What regularizeSurfaces changed.
struct RegularizationReport {
  int parallel = 0;        ///< surfaces whose direction was snapped to a shared parallel direction
  int orthogonal = 0;      ///< direction classes snapped to be exactly orthogonal to another one
  int coplanarMerged = 0;  ///< planes merged into a coplanar one
  int coaxial = 0;         ///< axial surfaces (and sphere centres) moved onto a shared axis
  int equalRadii = 0;      ///< radii (and cone angles) set to a shared value
  int duplicatesMerged = 0;  ///< curved surfaces merged into an identical one
  double maxRotation = 0.0;  ///< largest change of a normal or axis direction, radians
  double maxShift = 0.0;     ///< largest move of a plane or an axis, scan units

  /// One line for logs, e.g. "12 parallel, 3 orthogonal, 1 coplanar merged, ...".
  std::string summary() const;
};

/// Snaps the surfaces of `result` to exact relations, in place:
/// * plane normals and cylinder/cone/torus axes within angleTolerance of
///   parallel share one direction (the inlier-weighted mean); direction
///   classes within angleTolerance of orthogonal are made exactly orthogonal
///   (heavier classes first, so a frame is fixed by its largest faces);
/// * planes with the same oriented normal and offsets within
///   offsetTolerance x epsilon become one surface (inliers joined);
/// * axial surfaces with one direction and axis lines within
///   axisTolerance x epsilon share one axis line; sphere centres that close
///   to it move onto it;
/// * cylinder, sphere and torus radii within radiusTolerance x epsilon, and
///   cone half-angles within angleTolerance, become equal; surfaces that
///   become identical are merged.
/// Rotations pivot about each surface's inlier centroid (result.centroids;
/// when those are missing, about the surface's own reference point), so a
/// plane's offset remains the least-squares one for its new normal. Surface
/// indices change when surfaces merge; the assignment follows. rms values are
/// those of the refinement (not recomputed).
RegularizationReport regularizeSurfaces(DetectionResult& result,
                                        const RegularizeOptions& options = {});

}  // namespace csgvox
