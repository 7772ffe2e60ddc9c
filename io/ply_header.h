#pragma once
/// The header of a PLY file: its elements and properties, checked against
/// what the scan and mesh readers support and against the size of the data.
/// Parsed by hand to choose point cloud or mesh, to find normals and to check
/// the data is complete before CGAL reads it (CGAL asserts on integer
/// coordinates, skips unknown property types and misreads what follows).

#include <cstdint>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace csgvox::detail {

/// Encoding of the data after the header.
enum class PlyData { Ascii, LittleEndian, BigEndian };

/// One property of a PLY element.
struct PlyProperty {
  std::string name;       ///< property name ("x", "nx", "vertex_indices", ...)
  std::string type;       ///< value type (of the items, for a list)
  std::string countType;  ///< type of a list's length; empty for a scalar
};

/// One element of a PLY file ("vertex", "face", ...).
struct PlyElement {
  std::string name;                     ///< element name
  std::uint64_t count = 0;              ///< rows declared by the header (count)
  std::vector<PlyProperty> properties;  ///< properties of each row, in file order

  /// The property named `property`, or nullptr.
  const PlyProperty* find(std::string_view property) const;
};

/// A parsed PLY header. `vertices` and `faces` point into `elements`, so a
/// header must not be copied.
struct PlyHeader {
  PlyHeader() = default;
  PlyHeader(const PlyHeader&) = delete;
  PlyHeader& operator=(const PlyHeader&) = delete;
  PlyHeader(PlyHeader&&) = default;

  PlyData data = PlyData::Ascii;         ///< encoding of the data
  std::vector<PlyElement> elements;      ///< elements in file order
  std::uint64_t dataBytes = 0;           ///< bytes after end_header (count)
  std::size_t headerLines = 0;           ///< lines up to and including end_header (count)
  const PlyElement* vertices = nullptr;  ///< the vertex element (never null after parsing)
  const PlyElement* faces = nullptr;     ///< the face element, or null
  bool hasNormals = false;               ///< vertices have float nx, ny, nz
};

/// Size in bytes of a PLY scalar type, 0 if unknown.
int plyTypeSize(std::string_view type);

/// Parses the header of a PLY file from the stream's current position and
/// leaves the stream at the first byte of data.
/// @throw ParseError "<source>: ..." when the header is garbled, truncated,
///        lacks float x y z vertex properties, has a partial normal, faces
///        without an int vertex_indices list, or declares more data than the
///        file holds.
/// @throw IoError when the stream is not seekable.
PlyHeader parsePlyHeader(std::istream& in, const std::string& source);

/// Checks the data (from the stream's position, just after the header)
/// against the header before CGAL reads it. ASCII: each row on its own line
/// with exactly the values its properties declare, each a number of its
/// type. Binary: every list length fits in the rest of the file (CGAL sizes
/// a list from its stated length before reading the items). Both: nothing but
/// blanks after the last declared row.
/// @throw ParseError "<source>: ..." naming the line (ASCII) and the problem.
void checkPlyData(std::istream& in, const PlyHeader& header, const std::string& source);

/// "ply-ascii", "ply-binary-le" or "ply-binary-be".
std::string plyFormatName(PlyData data);

}  // namespace csgvox::detail
