#pragma once
/// Point-cloud files: the vertices of a PLY without faces, and XYZ text.
/// The points come back checked (finite coordinates, unit normals when the
/// file has them) but without normal estimation.

#include <iosfwd>
#include <string>

#include "core/point_cloud.h"
#include "io/ply_header.h"

namespace csgvox::detail {

/// Reads the vertices of a PLY point cloud whose header is `header` (the
/// stream is read again from its start). The cloud has normals, normalised,
/// when the header declares nx ny nz, otherwise none.
/// @throw ParseError "<source>: ..." when the data is truncated, holds a
///        value that is not a finite number, or a zero-length normal.
PointCloud readPlyPoints(std::istream& in, const PlyHeader& header, const std::string& source);

/// Reads "x y z" or "x y z nx ny nz" lines (blank lines, "#" comment lines
/// and an optional point count alone on the first line are skipped) from the
/// stream's position to its end. Every line must have the same number of
/// columns. The cloud has normals, normalised, when the lines have 6 columns.
/// @throw ParseError "<source>: line N: ..." for a line with another number
///        of columns than 3 or 6 or than the first line, a word that is not a
///        finite number, or a zero-length normal.
PointCloud readXyzPoints(std::istream& in, const std::string& source);

}  // namespace csgvox::detail
