#include "io/mesh_readers.h"

#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <istream>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <vector>

#include "io/errors.h"
#include "io/reader_support.h"

namespace csgvox::detail {
namespace {

using IoPoint = CGAL::Simple_cartesian<double>::Point_3;
using Polygon = std::vector<std::size_t>;

std::vector<Vec3> toVec3(const std::vector<IoPoint>& points) {
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (const IoPoint& p : points) out.emplace_back(p.x(), p.y(), p.z());
  return out;
}

/// Reads an ASCII OFF mesh. Written by hand because CGAL's OFF reader
/// allocates whatever vertex, face and per-face counts the file states
/// before reading them, so one garbled count exhausts memory.
PolygonSoup readOff(std::istream& in, const std::string& source) {
  const std::string text = slurp(in, source);
  std::size_t pos = 0;
  std::size_t lineNumber = 0;
  std::vector<std::string_view> words;
  // Moves to the next line with content (comments removed); false at the end.
  auto nextLine = [&]() {
    while (pos < text.size()) {
      const std::size_t end = std::min(text.find('\n', pos), text.size());
      std::string_view line(text.data() + pos, end - pos);
      pos = end + 1;
      ++lineNumber;
      words = splitWords(line.substr(0, line.find('#')));
      if (!words.empty()) return true;
    }
    return false;
  };
  auto fail = [&](const std::string& problem) {
    parseError(source, "line " + std::to_string(lineNumber) + ": " + problem);
  };

  const std::string notOff = "not an OFF file (it must start with \"OFF\")";
  if (!nextLine() || words[0].size() < 3 || !words[0].ends_with("OFF")) parseError(source, notOff);
  const std::string_view variant = words[0].substr(0, words[0].size() - 3);  // ST, C, N, 4, n
  if (variant.find_first_not_of("STCN4n") != std::string_view::npos) parseError(source, notOff);
  if (variant.find('n') != std::string_view::npos)
    parseError(source, "nOFF files are not supported");
  if (words.size() > 1 && words[1] == "BINARY") {
    parseError(source, "binary OFF is not supported (convert it to ASCII OFF or PLY)");
  }
  const bool homogeneous = variant.find('4') != std::string_view::npos;
  if (words.size() == 1 && !nextLine()) parseError(source, "truncated OFF header");
  const std::size_t first =
      words[0].ends_with("OFF") ? 1 : 0;  // counts may share the keyword's line
  std::uint64_t vertexCount = 0;
  std::uint64_t faceCount = 0;
  if (words.size() < first + 2 || !parseCount(words[first], vertexCount) ||
      !parseCount(words[first + 1], faceCount)) {
    fail("garbled OFF header (expected vertex, face and edge counts)");
  }
  // A vertex line takes at least 6 bytes ("0 0 0\n"), a face line 2.
  if (saturatingMulAdd(saturatingMulAdd(0, vertexCount, 6), faceCount, 2) > text.size()) {
    parseError(source, "truncated or garbled OFF file: the header declares " +
                           std::to_string(vertexCount) + " vertices and " +
                           std::to_string(faceCount) + " faces, more than its " +
                           std::to_string(text.size()) + " bytes can hold");
  }
  if (faceCount == 0) parseError(source, "mesh has no faces");

  PolygonSoup soup;
  soup.format = "off-mesh";
  soup.points.reserve(static_cast<std::size_t>(vertexCount));
  for (std::uint64_t v = 0; v < vertexCount; ++v) {
    if (!nextLine()) {
      parseError(source, "truncated OFF file (" + std::to_string(v) + " of " +
                             std::to_string(vertexCount) + " vertices)");
    }
    std::array<double, 4> c{0.0, 0.0, 0.0, 1.0};
    const std::size_t dims = homogeneous ? 4 : 3;
    for (std::size_t i = 0; i < dims; ++i) {  // colours, normals etc. may follow
      if (i >= words.size() || !parseFinite(words[i], c[i])) {
        fail("a vertex needs " + std::to_string(dims) + " coordinates that are finite numbers");
      }
    }
    if (c[3] == 0.0) fail("a vertex has the homogeneous coordinate 0");
    soup.points.emplace_back(c[0] / c[3], c[1] / c[3], c[2] / c[3]);
  }
  soup.polygons.reserve(static_cast<std::size_t>(faceCount));
  for (std::uint64_t f = 0; f < faceCount; ++f) {
    if (!nextLine()) {
      parseError(source, "truncated OFF file (" + std::to_string(f) + " of " +
                             std::to_string(faceCount) + " faces)");
    }
    std::uint64_t size = 0;
    if (!parseCount(words[0], size) || size >= words.size()) {  // a face colour may follow
      fail("a face needs its vertex count followed by that many vertex indices");
    }
    Polygon polygon(static_cast<std::size_t>(size));
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      std::uint64_t index = 0;
      if (!parseCount(words[i + 1], index) || index >= vertexCount) {
        fail("vertex index \"" + std::string(words[i + 1]) + "\" is out of range (the file has " +
             std::to_string(vertexCount) + " vertices)");
      }
      polygon[i] = static_cast<std::size_t>(index);
    }
    soup.polygons.push_back(std::move(polygon));
  }
  return soup;
}

PolygonSoup readObj(std::istream& in, const std::string& source) {
  std::string text = slurp(in, source);
  normalizeBlanks(text);
  if (!text.empty() && text.back() != '\n') text.push_back('\n');  // so a bad last line is found
  std::istringstream stream(text);
  std::vector<IoPoint> points;
  PolygonSoup soup;
  soup.format = "obj-mesh";
  bool ok = false;
  {
    CerrCapture quiet;
    ok = guarded(source, [&] {
      return CGAL::IO::read_OBJ(stream, points, soup.polygons, CGAL::parameters::verbose(false));
    });
  }
  if (!ok) {
    if (!stream.eof()) {
      // The reader stopped at a line it could not use.
      const std::streampos at = stream.tellg();
      const auto end = at < 0 ? text.end() : text.begin() + static_cast<std::ptrdiff_t>(at);
      const auto line = std::count(text.begin(), end, '\n');
      parseError(source, "line " + std::to_string(line) +
                             " is not a valid OBJ statement (or a vertex is not 3 finite numbers)");
    }
    if (points.empty()) parseError(source, "OBJ file has no vertices");
    if (soup.polygons.empty()) parseError(source, "mesh has no faces");
    parseError(source, "an OBJ face refers to a vertex that does not exist");
  }
  soup.points = toVec3(points);
  return soup;
}

PolygonSoup readStl(std::istream& in, const std::string& source) {
  const std::uint64_t size = bytesLeft(in, source);
  std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(size, 4096)), '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  rewindStream(in);
  std::uint64_t declared = 0;
  if (size >= 84) {
    for (int i = 0; i < 4; ++i) {
      declared |= std::uint64_t{static_cast<unsigned char>(head[80 + i])} << (8 * i);
    }
  }
  const bool binary = size >= 84 && size == 84 + 50 * declared;
  const std::size_t first = head.find_first_not_of(" \t\r\n");
  const bool text = std::none_of(head.begin(), head.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u < 9 || (u > 13 && u < 32);
  });
  const bool ascii =
      !binary && text && first != std::string::npos && head.compare(first, 5, "solid") == 0;
  if (!binary && !ascii) {
    if (size >= 84) {
      parseError(source, "truncated or garbled binary STL: the header declares " +
                             std::to_string(declared) + " triangles (" +
                             std::to_string(84 + 50 * declared) + " bytes) but the file has " +
                             std::to_string(size) + " bytes");
    }
    parseError(source, "not an STL file (no \"solid\" keyword and too short for binary STL)");
  }
  if (binary) {
    if (declared == 0) parseError(source, "mesh has no faces");
    // CGAL merges equal vertices in a std::map, where a NaN would silently
    // merge with anything: check coordinates first.
    in.seekg(84);
    std::array<char, 50> record{};
    for (std::uint64_t t = 0; t < declared; ++t) {
      if (!in.read(record.data(), 50)) throw IoError(source + ": read failed");
      for (int v = 3; v < 12; ++v) {
        std::uint32_t bits = 0;
        for (int b = 0; b < 4; ++b) {
          bits |= std::uint32_t{static_cast<unsigned char>(record[4 * v + b])} << (8 * b);
        }
        if (!std::isfinite(std::bit_cast<float>(bits))) {
          parseError(source, "triangle " + std::to_string(t + 1) + " has a non-finite coordinate");
        }
      }
    }
    rewindStream(in);
  }
  std::vector<IoPoint> points;
  std::vector<std::array<std::size_t, 3>> triangles;
  bool ok = false;
  {
    CerrCapture quiet;
    ok = guarded(source, [&] {
      return CGAL::IO::read_STL(in, points, triangles, CGAL::parameters::verbose(false));
    });
  }
  if (!ok || (binary && triangles.size() != declared)) {
    parseError(source, binary ? "binary STL data is unreadable"
                              : "ASCII STL is truncated or garbled (a facet without 3 vertices, a "
                                "value that is not a finite number, or no endsolid)");
  }
  if (triangles.empty()) parseError(source, "mesh has no faces");
  PolygonSoup soup;
  soup.format = binary ? "stl-binary-mesh" : "stl-ascii-mesh";
  soup.points = toVec3(points);
  soup.polygons.reserve(triangles.size());
  for (const auto& t : triangles) soup.polygons.push_back({t[0], t[1], t[2]});
  return soup;
}

/// Checks what every mesh reader must deliver: faces, finite coordinates and
/// indices that name vertices of the file.
void checkSoup(const PolygonSoup& soup, const std::string& source) {
  const std::size_t n = soup.points.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!soup.points[i].allFinite()) {
      parseError(source, "vertex " + std::to_string(i + 1) + " has a non-finite coordinate");
    }
  }
  if (soup.polygons.empty()) parseError(source, "mesh has no faces");
  for (std::size_t f = 0; f < soup.polygons.size(); ++f) {
    for (std::size_t v : soup.polygons[f]) {
      if (v >= n) {
        parseError(source, "face " + std::to_string(f + 1) + " refers to vertex " +
                               std::to_string(v + 1) + " (counting from 1), but the file has " +
                               std::to_string(n) + " vertices");
      }
    }
  }
}

}  // namespace

PolygonSoup readPlyMesh(std::istream& in, const PlyHeader& header, const std::string& source) {
  std::vector<IoPoint> points;
  PolygonSoup soup;
  soup.format = plyFormatName(header.data) + "-mesh";
  rewindStream(in);
  bool ok = false;
  {
    CerrCapture quiet;
    ok = guarded(source, [&] {
      return CGAL::IO::read_PLY(in, points, soup.polygons, CGAL::parameters::verbose(false));
    });
  }
  if (!ok || points.size() != header.vertices->count ||
      soup.polygons.size() != header.faces->count) {
    parseError(source, "PLY mesh data is truncated or unreadable (read " +
                           std::to_string(points.size()) + " of " +
                           std::to_string(header.vertices->count) + " vertices and " +
                           std::to_string(soup.polygons.size()) + " of " +
                           std::to_string(header.faces->count) + " faces)");
  }
  soup.points = toVec3(points);
  return soup;
}

PolygonSoup readPolygonSoup(std::istream& in, ScanFileType type, const std::string& source) {
  if (!in) throw IoError(source + ": cannot be read");
  rewindStream(in);
  if (bytesLeft(in, source) == 0) parseError(source, "file is empty");
  PolygonSoup soup;
  switch (type) {
    case ScanFileType::Ply: {
      const PlyHeader header = parsePlyHeader(in, source);
      checkPlyData(in, header, source);
      if (!header.faces || header.faces->count == 0) parseError(source, "mesh has no faces");
      soup = readPlyMesh(in, header, source);
      break;
    }
    case ScanFileType::Off:
      soup = readOff(in, source);
      break;
    case ScanFileType::Obj:
      soup = readObj(in, source);
      break;
    case ScanFileType::Stl:
      soup = readStl(in, source);
      break;
    case ScanFileType::Xyz:
      throw std::invalid_argument("readPolygonSoup: XYZ is not a mesh format");
  }
  checkSoup(soup, source);
  return soup;
}

}  // namespace csgvox::detail
