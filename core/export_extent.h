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

/// The box that the stand-ins of the tree's half-spaces and complements
/// cover: the bounds of every bounded primitive of the tree, with the tree's
/// own bounds when those are finite (a block cut from half-spaces). Every
/// operand a half-space is combined with lies in it, so a stand-in that
/// agrees with its half-space in this box gives the tree's exact solid
/// (a primitive that reaches far outside the part, as a large fitted
/// cylinder, is cut where it lies, not where the part does).
/// @throw std::invalid_argument as exportExtent().
Aabb standInExtent(const CsgTree& tree);

/// The cube standing in for `halfSpace` in `extent` (standInExtent()): its
/// top face lies in the half-space's plane, centred on the point of the
/// plane nearest the extent's centre. Its edge is `edge`, or more where the
/// plane lies far beyond the extent's centre: with `edge` at least the
/// extent's diagonal the cube holds every point of the extent inside the
/// half-space.
StandInCube halfSpaceCube(const HalfSpace& halfSpace, const Aabb& extent, double edge);

/// The world-aligned cube of edge `edge` centred on the extent: the
/// "everything" a complement is cut from.
StandInCube surroundingCube(const Aabb& extent, double edge);

}  // namespace csgvox
