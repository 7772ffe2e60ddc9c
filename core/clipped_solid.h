#pragma once
/// The solid bounded by an unbounded fitted surface, as a csgvox primitive
/// that is exact inside a given box. Fitted surfaces (core/surface.h) are
/// unbounded; csgvox primitives (core/primitive.h) are bounded except the
/// half-space. A capped cylinder or a cone frustum long enough that its caps
/// never come nearer to a point of the box than its lateral surface has, at
/// every point of the box, the same signed distance as the infinite solid.

#include "core/geometry.h"
#include "core/primitive.h"
#include "core/surface.h"

namespace csgvox {

/// The solid bounded by an unbounded surface (f >= 0 inside: a plane's
/// half-space behind its normal, the inside of a cylinder/cone/sphere/torus),
/// as a csgvox primitive whose value equals the unbounded solid's exact signed
/// distance at every point of `box` (up to rounding):
/// - a plane {normal·x = offset} → HalfSpace{normal, offset}, the solid
///   {normal·x <= offset};
/// - a sphere → Sphere, a torus → Torus, unchanged;
/// - a cylinder → a capped Cylinder on the same axis, centred on the
///   projection of the box's centre onto the axis, whose caps are farther from
///   every point of `box` than the box's diagonal plus the radius (so also
///   farther than the lateral surface is from any point of the box inside it);
/// - a cone → a Cone frustum from the apex (radiusBottom 0 at the apex) along
///   axisDir, of height 2·R + diagonal where R is the largest distance from
///   the apex to the box: its top cap is farther from every point of `box`
///   than R + diagonal, hence farther than the cone's surface is.
///
/// The cone is the one-sided infinite cone {z >= 0, rho <= z·tan(halfAngle)}
/// (z along axisDir from the apex, rho the distance to the axis). Its exact
/// signed distance is z·sin(a) − rho·cos(a) when z·cos(a) + rho·sin(a) > 0 and
/// −|p − apex| otherwise: points behind the apex (in the region whose nearest
/// point of the surface is the apex) are outside at their distance to the
/// apex. The frustum's value there is the distance to its lateral surface near
/// the apex, which is the same.
///
/// @throw std::invalid_argument when `box` is empty or unbounded, or the
///        surface is invalid: a non-finite parameter, an axis or normal that
///        is not unit, a radius <= 0, a cone half-angle outside (0, pi/2), a
///        torus whose minor radius exceeds its major radius (a spindle torus).
Primitive clippedSolid(const SurfaceShape& shape, const Aabb& box);

}  // namespace csgvox
