#pragma once
/// Normal estimation for scans that come without normals.

#include <cstdint>
#include <vector>

#include "core/point_cloud.h"

namespace csgvox {

/// Estimates a unit outward normal for every point of `cloud`, replacing any
/// normals it has. Copies of a point share one normal, estimated once (copies
/// would make degenerate neighbourhoods).
/// 1. a jet (quadric) fit to the point's `neighbors` nearest neighbours;
/// 2. near sharp edges, where such a fit blends the two faces, the normal of
///    the neighbour whose tangent plane holds most of the neighbourhood;
///    where a neighbourhood lies on two parallel sheets (the faces of a wall
///    thinner than it, the point's own face often holding the fewer points),
///    the normal of both sheets fitted together, when at least 2 % of the
///    scan's points show such sheets (the scan has thin walls);
/// 3. orientations propagated along a minimum spanning forest of the
///    neighbour graph (Hoppe's method, with edges that cross the surface,
///    e.g. through a thin wall, made expensive); pieces the graph does not
///    connect are matched to the largest piece by their closest points; all
///    normals flipped if, at the scan's extreme points along ±x, ±y, ±z,
///    they mostly point inwards;
/// 4. orientNormals: smooth patches that visibility from outside shows
///    clearly (flat caps, bores, which the spanning forest may turn over
///    as a whole) take the side it shows; on a scan with thin walls, the
///    patches it leaves open take theirs from a decided face across the
///    wall.
///
/// Reliable for scans of closed surfaces sampled densely relative to their
/// features; walls much thinner than the neighbourhood may still come out
/// wrong. Deterministic for a given cloud, with any number of threads (the
/// jet fits run in parallel).
/// @throw std::invalid_argument if `neighbors` < 6, if a point is not finite,
///        if the cloud has no more than `neighbors` distinct positions (in
///        particular, if all its points are at one position), or if no
///        neighbourhood spans a surface (all points on a line).
void estimateNormals(PointCloud& cloud, int neighbors);

/// The unit normal, unoriented, of a jet (a quadric) fitted to the points
/// `hood` of `points`, the first of them the origin of the fit: as CGAL's
/// Monge_via_jet_fitting (jet degree 2, Monge degree 1) gives it, to
/// rounding, at about a quarter of its cost (fixed-capacity matrices, a QR
/// where the system has full rank, the least-norm solution of an SVD where
/// it has not). Zero when the points span no surface (their second
/// principal variance at most 1e-12 of their first: a line up to rounding).
/// @throw std::invalid_argument if `hood` has fewer than 6 points.
Vec3 jetNormal(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& hood);

/// The same normal by CGAL's general jet fitting (dynamic matrices, an SVD
/// per point), without jetNormal's test for a line: what jetNormal gives
/// for more than 64 points that span a surface.
/// @throw std::invalid_argument if `hood` has fewer than 6 points.
Vec3 generalJetNormal(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& hood);

/// How far a cloud's own normals agree with its local surface: the fraction
/// of the points whose normal lies within 30 degrees, sign ignored, of the
/// normal of the plane through its `neighbors` nearest neighbours among
/// those whose normals face its way (within about 70 degrees; the other face
/// of a thin wall stays out), over a deterministic subset of at most 4000
/// points. Where those neighbourhoods are not flat (points dense against
/// their noise), they widen until they are. Neighbourhoods that span no
/// surface are not counted. The bundled scans' sampled normals read 0.72 to
/// 1, normals in random directions 0.1 to 0.18. 1 for a cloud of no more
/// than `neighbors` points.
/// @throw std::invalid_argument if `neighbors` < 3 or the cloud has no normals.
double normalAgreement(const PointCloud& cloud, int neighbors);

}  // namespace csgvox
