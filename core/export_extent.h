#pragma once
/// The finite stand-ins of unbounded sets in exports whose formats have no
/// half-spaces (OpenSCAD programs and CSG files, STEP): cubes much larger
/// than the part, placed so that they clip the part exactly as the
/// half-space or the complement does.

#include "core/csg_tree.h"

namespace csgvox {

/// A cube: `frame` (columns: its unit axes, right-handed), `center`, `edge`.
struct StandInCube {
  Mat3 frame = Mat3::Identity();  ///< the cube's axes
  Vec3 center = Vec3::Zero();     ///< its centre
  double edge = 1.0;              ///< edge length, scan units
};

/// The same box described with the permutation and signs of its axes
/// closest to the world axes (a right-handed frame), so that a box aligned
/// with the world axes gets the identity frame.
Box canonicalBox(const Box& box);

/// The part's extent: the bounds of the tree's bounded primitives, cut to
/// the tree's own bounds when those are finite.
/// @throw std::invalid_argument for an empty tree or one whose bounded
///        primitives give no extent.
Aabb exportExtent(const CsgTree& tree);

/// The cube of edge `edge` standing in for `halfSpace` near `extent`: its top
/// face lies in the half-space's plane, centred on the point of the plane
/// nearest the extent's centre, so that it covers the part's side of the
/// plane when `edge` is at least twice the extent's diagonal.
StandInCube halfSpaceCube(const HalfSpace& halfSpace, const Aabb& extent, double edge);

/// The world-aligned cube of edge `edge` centred on the extent: the
/// "everything" a complement is cut from.
StandInCube surroundingCube(const Aabb& extent, double edge);

}  // namespace csgvox
