#pragma once
/// Mesh files: PLY, STL and OBJ out; STL (ASCII and binary), OFF, OBJ and PLY in.

#include "core/triangle_mesh.h"

#include <filesystem>
#include <iosfwd>

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
/// @throw IoError when the file is missing, unreadable or has another
///        extension.
/// @throw ParseError when the content is not a valid mesh (bad syntax, no
///        triangles, index out of range, non-finite coordinate).
TriangleMesh readMesh(const std::filesystem::path& path);

}  // namespace csgvox
