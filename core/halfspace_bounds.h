#pragma once
/// Bounds of an intersection of half-spaces: the axis-aligned box of the
/// convex polyhedron they cut out of a box, so that a solid made of planes
/// only (a block cut from six half-spaces) has finite bounds.

#include <span>

#include "core/geometry.h"
#include "core/primitive.h"

namespace csgvox {

/// The axis-aligned bounds of {x in box : normal·x <= offset for every
/// half-space}. `box` may be unbounded in any direction; a direction in which
/// the polyhedron is unbounded stays infinite; finite sides are widened by
/// 1e-9 of the largest offset or box coordinate, so the bounds stay
/// conservative under rounding. Empty when the half-spaces
/// leave nothing of the box (up to a relative tolerance of 1e-9).
Aabb halfSpaceIntersectionBounds(std::span<const HalfSpace> halfSpaces, const Aabb& box);

}  // namespace csgvox
