#include "io/mesh_files.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "core/decimal.h"
#include "io/errors.h"
#include "io/file_util.h"
#include "io/mesh_readers.h"

namespace csgvox {
namespace {

// Appends the little-endian bytes of a 32-bit value to `buffer`.
template <class T>
void putLittleEndian(std::string& buffer, T value) {
  static_assert(sizeof(T) == 4 && std::is_trivially_copyable_v<T>);
  std::uint32_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  for (int i = 0; i < 4; ++i) buffer.push_back(static_cast<char>((bits >> (8 * i)) & 0xffu));
}

void putFloat(std::string& buffer, double value) {
  putLittleEndian(buffer, static_cast<float>(value));
}

void requireValidIndices(const TriangleMesh& mesh) {
  const std::size_t n = mesh.vertices.size();
  for (const auto& t : mesh.triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n) {
      throw std::invalid_argument("mesh triangle index " +
                                  std::to_string(std::max({t[0], t[1], t[2]})) +
                                  " is out of range (" + std::to_string(n) + " vertices)");
    }
  }
}

// Large meshes are written in chunks of about this many bytes.
constexpr std::size_t kChunkBytes = 1 << 20;

void flushIfFull(std::ostream& out, std::string& buffer) {
  if (buffer.size() >= kChunkBytes) {
    out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    buffer.clear();
  }
}

void flushAll(std::ostream& out, std::string& buffer) {
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  buffer.clear();
}

}  // namespace

void writeMeshPly(std::ostream& out, const TriangleMesh& mesh) {
  requireValidIndices(mesh);
  std::string buffer = "ply\nformat binary_little_endian 1.0\ncomment written by csgvox\n";
  buffer += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
  buffer += "property float x\nproperty float y\nproperty float z\n";
  buffer += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  buffer += "property list uchar uint vertex_indices\nend_header\n";
  for (const Vec3& v : mesh.vertices) {
    for (int k = 0; k < 3; ++k) putFloat(buffer, v[k]);
    flushIfFull(out, buffer);
  }
  for (const auto& t : mesh.triangles) {
    buffer.push_back(3);
    for (int k = 0; k < 3; ++k) putLittleEndian(buffer, t[k]);
    flushIfFull(out, buffer);
  }
  flushAll(out, buffer);
}

void writeMeshStl(std::ostream& out, const TriangleMesh& mesh) {
  requireValidIndices(mesh);
  if (mesh.triangles.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("binary STL holds at most 2^32 - 1 triangles");
  }
  // The header must not start with "solid", which marks ASCII STL.
  std::string buffer = "binary STL written by csgvox";
  buffer.resize(80, ' ');
  putLittleEndian(buffer, static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[t[0]];
    const Vec3& b = mesh.vertices[t[1]];
    const Vec3& c = mesh.vertices[t[2]];
    Vec3 normal = (b - a).cross(c - a);
    const double length = normal.norm();
    normal = length > 0.0 ? Vec3(normal / length) : Vec3::Zero();
    for (const Vec3* p : std::array<const Vec3*, 4>{&normal, &a, &b, &c}) {
      for (int k = 0; k < 3; ++k) putFloat(buffer, (*p)[k]);
    }
    buffer.append(2, '\0');  // attribute byte count
    flushIfFull(out, buffer);
  }
  flushAll(out, buffer);
}

void writeMeshObj(std::ostream& out, const TriangleMesh& mesh) {
  requireValidIndices(mesh);
  std::string buffer = "# written by csgvox\n";
  for (const Vec3& v : mesh.vertices) {
    buffer += "v";
    for (int k = 0; k < 3; ++k) {
      buffer += ' ';
      appendDecimal(buffer, v[k]);
    }
    buffer += '\n';
    flushIfFull(out, buffer);
  }
  for (const auto& t : mesh.triangles) {
    buffer += "f";
    for (int k = 0; k < 3; ++k) {
      buffer += ' ';
      buffer += std::to_string(std::uint64_t{t[k]} + 1);
    }
    buffer += '\n';
    flushIfFull(out, buffer);
  }
  flushAll(out, buffer);
}

void writeMesh(const std::filesystem::path& path, const TriangleMesh& mesh) {
  const std::string ext = lowerExtension(path);
  void (*write)(std::ostream&, const TriangleMesh&) = nullptr;
  if (ext == "ply") {
    write = writeMeshPly;
  } else if (ext == "stl") {
    write = writeMeshStl;
  } else if (ext == "obj") {
    write = writeMeshObj;
  } else {
    throw IoError(path.string() + ": unsupported mesh format '" + path.extension().string() +
                  "' (expected .ply, .stl or .obj)");
  }
  writeFileAtomically(
      path, [&](std::ostream& out) { write(out, mesh); }, ext != "obj");
}

TriangleMesh readMesh(std::istream& in, ScanFileType type, const std::string& source) {
  if (type == ScanFileType::Xyz) {
    throw std::invalid_argument("readMesh: XYZ is a point format, not a mesh format");
  }
  const detail::PolygonSoup soup = detail::readPolygonSoup(in, type, source);
  if (soup.points.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw ParseError(source + ": too many vertices (at most 2^32 - 1)");
  }
  TriangleMesh mesh;
  mesh.vertices = soup.points;
  mesh.triangles.reserve(soup.polygons.size());
  for (std::size_t f = 0; f < soup.polygons.size(); ++f) {
    const std::vector<std::size_t>& polygon = soup.polygons[f];
    if (polygon.size() < 3) {
      throw ParseError(source + ": face " + std::to_string(f + 1) + " has fewer than 3 vertices");
    }
    // A fan around the first corner (exact for convex polygons).
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
      mesh.triangles.push_back({static_cast<std::uint32_t>(polygon[0]),
                                static_cast<std::uint32_t>(polygon[i]),
                                static_cast<std::uint32_t>(polygon[i + 1])});
    }
  }
  return mesh;
}

TriangleMesh readMesh(const std::filesystem::path& path) {
  requireReadableFile(path);
  const std::string ext = lowerExtension(path);
  if (ext != "stl" && ext != "off" && ext != "obj" && ext != "ply") {
    throw IoError(path.string() + ": unsupported mesh format '" + path.extension().string() +
                  "' (expected .stl, .off, .obj or .ply)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot be opened for reading");
  return readMesh(in, scanFileTypeFromPath(path), path.string());
}

}  // namespace csgvox
