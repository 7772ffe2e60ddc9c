#pragma once
/// Near-coincident faces made coincident: a tree fitted to a scan places
/// the flat caps of its primitives (box faces, cylinder and cone ends,
/// half-space planes) independently, so faces that meet on the part (a
/// shaft's shoulder, a boss on a plate) end up a few hundredths of a
/// millimetre apart or overlapping. Exact booleans then return several
/// solids separated by slivers, or misclassify faces that nearly coincide.
/// Snapping moves such caps onto one plane (and aligns nearly parallel
/// axes exactly), which changes the solid by far less than the scan can
/// tell.

#include <cstddef>

#include "core/csg_tree.h"

namespace csgvox {

/// Options of snapFaces().
struct FaceSnapOptions {
  double tolerance = 0.0;      ///< caps closer than this are moved onto one plane, scan units
  double angle = 1e-6;         ///< directions closer than this are made equal, radians
  bool torusEquator = true;    ///< a torus's equator plane holds the caps near it
  bool torusTangents = false;  ///< so do the two planes tangent to its tube
};

/// What snapFaces() changed.
struct FaceSnapResult {
  CsgTree tree;                ///< the tree with snapped directions and caps
  std::size_t movedCaps = 0;   ///< caps moved onto another cap's plane (any distance > 0)
  double largestMove = 0.0;    ///< largest distance a cap moved, scan units
  std::size_t turnedAxes = 0;  ///< directions replaced by a nearly parallel one
};

/// Aligns directions (half-space normals, box axes, cylinder, cone and
/// torus axes) closer than `options.angle` to one of them (a coordinate
/// axis when one is that close), then groups the parallel flat caps whose
/// planes lie within `options.tolerance` of the group's first and moves
/// them onto the plane of the group's largest caps (the area-weighted
/// median; a half-space's plane first, then a torus's equator and, when
/// asked, the planes tangent to its tube, which stay where they are). A
/// cone keeps its lateral surface (its
/// cap radii follow the caps); a primitive whose caps would come closer
/// than half their distance keeps its own. Names and shared subtrees are
/// kept; spheres and tori (apart from their axes) are unchanged.
/// @throw std::invalid_argument when the tolerance is negative.
FaceSnapResult snapFaces(const CsgTree& tree, const FaceSnapOptions& options);

}  // namespace csgvox
