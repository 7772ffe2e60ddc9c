#pragma once
/// Mesh files read as polygon soups: PLY with faces, OFF, OBJ and STL. One
/// reader per format, shared by the scan reader (which samples the faces)
/// and readMesh (which splits them into triangles).

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "io/ply_header.h"
#include "io/scan_reader.h"

namespace csgvox::detail {

/// Polygons over shared vertices, as a mesh file states them.
struct PolygonSoup {
  std::vector<Vec3> points;                        ///< vertex positions
  std::vector<std::vector<std::size_t>> polygons;  ///< 0-based vertex indices, as in the file
  std::string
      format;  ///< "off-mesh", "obj-mesh", "stl-ascii-mesh", "stl-binary-mesh", "ply-...-mesh"
};

/// Reads the vertices and faces of a PLY whose header is `header` (the
/// stream is read again from its start).
/// @throw ParseError when the data is truncated or unreadable.
PolygonSoup readPlyMesh(std::istream& in, const PlyHeader& header, const std::string& source);

/// Reads a mesh of the given type (not Xyz) from a seekable stream, from
/// position 0 to its end. The soup is checked: at least one face, finite
/// coordinates, every index names a vertex of the file. Faces may still be
/// degenerate (fewer than 3 distinct corners).
/// @throw ParseError "<source>: ..." for content that is not a valid mesh
///        (bad syntax, truncated, no faces, index out of range, non-finite
///        coordinate; a PLY without faces).
/// @throw IoError when the stream cannot be read or is not seekable.
/// @throw std::invalid_argument for ScanFileType::Xyz.
PolygonSoup readPolygonSoup(std::istream& in, ScanFileType type, const std::string& source);

}  // namespace csgvox::detail
