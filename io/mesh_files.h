#pragma once
/// Mesh files: PLY, STL and OBJ out; STL (ASCII and binary), OFF, OBJ and PLY in.

#include <filesystem>
#include <iosfwd>
#include <string>

#include "core/triangle_mesh.h"
#include "io/scan_reader.h"

namespace csgvox {

/// Writes `mesh` to `path` in the format named by the extension: `.ply`
/// (binary little endian), `.stl` (binary) or `.obj` (case-insensitive). The
/// file is replaced atomically.
/// @throw IoError for another extension or when the file cannot be written.
/// @throw std::invalid_argument when a triangle index is out of range.
void writeMesh(const std::filesystem::path& path, const TriangleMesh& mesh);

/// Writes `mesh` as binary little-endian PLY (float coordinates) to `out`,
/// which must be opened in binary mode.
/// @throw std::invalid_argument when a triangle index is out of range.
void writeMeshPly(std::ostream& out, const TriangleMesh& mesh);

/// Writes `mesh` as binary STL (float coordinates, one facet normal per
/// triangle) to `out`, which must be opened in binary mode.
/// @throw std::invalid_argument when a triangle index is out of range or the
///        mesh has more than 2^32 - 1 triangles.
void writeMeshStl(std::ostream& out, const TriangleMesh& mesh);

/// Writes `mesh` as Wavefront OBJ text (shortest round-trip decimal
/// coordinates, 1-based indices) to `out`.
/// @throw std::invalid_argument when a triangle index is out of range.
void writeMeshObj(std::ostream& out, const TriangleMesh& mesh);

/// Reads a mesh from `.stl` (ASCII or binary), `.off`, `.obj` or `.ply`
/// (ASCII or binary), chosen by the extension. Polygons with more than three
/// corners are split into triangle fans. STL vertices with identical
/// coordinates are merged, so a closed STL solid reads back closed.
/// The file is read by the same strict readers as readScan's meshes.
/// @throw IoError when the file is missing, not a regular file, unreadable
///        or has another extension.
/// @throw ParseError when the content is not a valid mesh (bad syntax,
///        truncated, no faces, a face with fewer than 3 corners, index out of
///        range, non-finite coordinate, more than 2^32 - 1 vertices).
TriangleMesh readMesh(const std::filesystem::path& path);

/// Reads a mesh of the given type from a seekable stream opened in binary
/// mode, from position 0 to its end; `source` names the input in error
/// messages. Otherwise as readMesh(path).
/// @throw ParseError "<source>: ..." for invalid content (as readMesh(path)).
/// @throw IoError when the stream cannot be read or is not seekable.
/// @throw std::invalid_argument for ScanFileType::Xyz.
TriangleMesh readMesh(std::istream& in, ScanFileType type, const std::string& source = "<stream>");

}  // namespace csgvox
