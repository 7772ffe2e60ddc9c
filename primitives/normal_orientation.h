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
///    not lie across each other's tangent planes (off by more than 0.15 of
///    their distance and 3 times the noise, a low quantile of the
///    neighbourhoods' residuals: the two faces of a thin wall) join one
///    patch; within a patch the normals are made consistent.
///    Thin walls: a neighbourhood whose offsets along the normal fall into
///    two groups (the largest gap between them over 3 times their spread,
///    at least 3 points each side) spans both faces of a wall thinner than
///    itself. Where a patch holds both faces (at least 4 % of its points,
///    and 50, see one of its points beyond that gap: the faces joined
///    where a rim narrower than the neighbourhoods runs between them), the
///    scan has thin walls and its patches are flooded again: the noise is
///    then measured over each neighbourhood's own face, neighbours beyond
///    the first jump of 3 times the noise on either side of a point lie on
///    another face, and a point joins a patch only if no patch point in its
///    neighbourhood does (by those jumps, or by an offset along the patch's
///    first normal over 0.75 of their distance and 3 times the noise).
///    Exact points (noise over one face below 1e-6 of the spacing: sampled
///    from a mesh, not scanned) are not searched for thin walls: without
///    noise every edge or curved neighbourhood shows such a gap.
///    Elsewhere the noise is a low quantile of the whole neighbourhoods'
///    residuals and the patches are flooded once.
/// 2. Visibility: rays march through an occupancy grid of the points (cells
///    one median spacing wide, each point filling its own spacing), starting
///    clear of the point's own layer. Parity rays, along +n and -n and four
///    tilted by 30 degrees on each side: one that crosses the surface an even
///    number of times before it leaves the grid started outside, so flat
///    caps, bores and faces in a concavity vote alike. Escape rays, 96
///    directions over the sphere within 60 degrees of +n or -n: where some
///    leave the grid without meeting any surface on one side only, that side
///    is outside (a face inside a concavity, whose parity rays may pass
///    through walls the scanner never saw, is seen through its opening);
///    escapes on both sides (out of the material through a face never seen)
///    leave the vote to parity. A face with a parallel face close across its
///    tangent plane on one side (a thin wall or slot, closer than the grid
///    resolves) votes with the other side's rays only.
/// 3. A patch whose points vote clearly (mean vote at least 0.35 of the
///    full vote) takes that side. Undecided patches joined by smooth edges
///    (a curved face the patches' cones split, such as a spherical seat deep
///    in a bore, whose patches each see little of the outside) form
///    clusters; a cluster takes the side its decided neighbours imply
///    across those edges when their votes are significant (vote sum at
///    least 4 times the square root of their count), they agree (on 90 %
///    of the edges) and the cluster's own votes do not lean the other way.
///    With `thinWalls` (the scan's walls are thinner than its
///    neighbourhoods: estimateNormals found two parallel sheets in 2 % of
///    them), a patch that no significant vote or cluster decided takes its
///    side from firmly decided faces close across its tangent plane and
///    nearly straight across: where such a face's outside points away from
///    the patch, the gap is material (a wall) and the patch faces away from
///    it; where it points towards the patch, the gap is air (a slot) and the
///    patch faces it. Both faces of a wall look alike to the rays: the
///    occupancy grid counts them as one crossing, and its inner face, seen
///    at grazing angles, falls into patches of a few points whose few rays
///    decide nothing.
///    The other patches (faces next to an unseen one, where
///    both sides look alike) keep the incoming normals.
///
/// `neighbours` holds k indices per point, the point itself first (its k
/// nearest neighbours). Deterministic with any number of threads.
/// @throw std::invalid_argument if the sizes disagree or k < 2.
void orientNormals(std::span<const Vec3> points, std::span<Vec3> normals,
                   std::span<const std::uint32_t> neighbours, unsigned k, bool thinWalls = false);

}  // namespace csgvox
