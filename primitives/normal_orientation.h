#pragma once
/// Outward orientation of normals by visibility from outside.

#include <cstdint>
#include <span>

#include "core/geometry.h"

namespace csgvox {

/// Flips normals so that they point out of the solid the points bound,
/// where visibility from outside says so clearly; elsewhere the normals keep
/// the orientation they come with (a provisional one, e.g. from a spanning
/// tree of the neighbour graph).
///
/// 1. Smooth patches: neighbours whose normals are within 25 degrees (sign
///    ignored), within 40 degrees of the patch's first normal, and which do
///    not lie across each other's tangent planes (the two faces of a thin
///    wall) join one patch; within a patch the normals are made consistent.
/// 2. Visibility: rays along +n and -n (and four rays tilted by 30 degrees on
///    each side) march through an occupancy grid of the points (cells twice
///    the median spacing, each point filling its own spacing), starting
///    clear of the point's own layer; a ray that crosses the surface an even
///    number of times before it leaves the grid started outside, so flat
///    caps, bores and faces in a concavity vote alike.
/// 3. A patch whose points vote clearly (mean vote at least 0.35 of the
///    full vote) takes that side; the others (thin walls, where both sides
///    look alike, faces next to an unseen one) keep the incoming normals.
///
/// `neighbours` holds k indices per point, the point itself first (its k
/// nearest neighbours). Deterministic with any number of threads.
/// @throw std::invalid_argument if the sizes disagree or k < 2.
void orientNormals(std::span<const Vec3> points, std::span<Vec3> normals,
                   std::span<const std::uint32_t> neighbours, unsigned k);

}  // namespace csgvox
