#pragma once
/// Square edges of a thin sheet read as full rounds. Normals estimated from
/// raw points turn continuously across a sheet only a few point spacings
/// thick, so the edge where a face meets a hole's wall or the sheet's end
/// looks like a round whose radius is half the sheet's thickness: detection
/// fits a convex torus along a hole's rim and a convex cylinder along a free
/// edge. Such a surface, between two opposite parallel faces that thin, on
/// their mid-plane and of half their distance in radius, is the sheet's edge:
/// a torus is dropped (the hole it hid is then found from its rims), a
/// cylinder becomes the end face, placed where its outermost points are.
/// Where two such sheets meet at a right angle, the blended corner reads as
/// a convex cylinder of about the thickness in radius; it is dropped when
/// the scan's points reach the square corner's outer line. The blend along
/// an edge also reads as a narrow plane tilted from the faces; it is
/// dropped.

#include <cstddef>

#include "core/point_cloud.h"
#include "primitives/surface_detection.h"

namespace csgvox {

/// Parameters of replaceSheetRounds.
struct SheetRoundOptions {
  /// A sheet is thin when its faces are at most this many point spacings of
  /// its faces apart (ratio): estimated normals blend across it (their
  /// neighbourhoods reach about 2.5 spacings each way).
  double maxThicknessSpacings = 6.0;
  /// The round's radius is half the thickness within this fraction of it
  /// (ratio), and its axis (a torus's circle) lies within this fraction of
  /// the thickness of the mid-plane.
  double tolerance = 0.35;
};

/// What replaceSheetRounds did.
struct SheetRoundStats {
  std::size_t tori = 0;       ///< tori along a hole's rim dropped
  std::size_t cylinders = 0;  ///< cylinders along a free edge made end faces
  std::size_t corners = 0;    ///< cylinders in the corner of two sheets dropped
  std::size_t tilted = 0;     ///< planes tilted along a sheet's edge dropped
};

/// Drops each convex torus of `result` that is a thin sheet's hole rim
/// (axis along two opposite parallel faces' normal, circle on their
/// mid-plane, minor radius half their distance, both faces' points along it)
/// and replaces each convex cylinder that is a thin sheet's free edge (axis
/// parallel to both faces, on their mid-plane, radius half their distance,
/// both faces' points along it) by the end face: a plane across the sheet
/// facing away from it, at the median of the cylinder's 8 outermost points
/// (the end face's own, or the faces' last before the edge), or by nothing
/// when such a plane is there already. Drops each convex cylinder in the
/// square corner of two thin sheets at a right angle (axis along their
/// common edge, inside both slabs, radius from 15 % of the thinner's
/// thickness to 135 % of the thicker's, at least 8 of the scan's points on
/// the corner's outer line along its span). Drops each plane tilted by 5 to
/// 35 degrees from a thin sheet's faces with 80 % of its points inside the
/// sheet's slab and at most a tenth as many points as the smaller face. The
/// end face holds the cylinder's
/// points within two noise deviations of it; the other points of a dropped
/// surface are unassigned. For estimated normals only (a scanner's own, or
/// exact ones, tell a round from an edge). `result` must be the output of
/// fitSurfaces (its centroids are kept up to date).
SheetRoundStats replaceSheetRounds(const PointCloud& cloud, DetectionResult& result,
                                   const SheetRoundOptions& options = {});

}  // namespace csgvox
