#include "io/scan_reader.h"

#include "io/errors.h"
#include "io/file_util.h"
#include "primitives/normal_estimation.h"

#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>
#include <CGAL/IO/read_ply_points.h>
#include <CGAL/IO/read_xyz_points.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <numeric>
#include <optional>
#include <random>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <vector>

namespace csgvox {
namespace {

// Reading, merging duplicate vertices and orienting a soup need only
// coordinate comparisons, no geometric predicates: a plain kernel will do.
using IoKernel = CGAL::Simple_cartesian<double>;
using IoPoint = IoKernel::Point_3;
using IoVector = IoKernel::Vector_3;
using PointNormal = std::pair<IoPoint, IoVector>;
using Polygon = std::vector<std::size_t>;

[[noreturn]] void parseError(const std::string& source, const std::string& problem) {
  throw ParseError(source + ": " + problem);
}

/// Number of bytes between the current position and the end of the stream.
std::uint64_t bytesLeft(std::istream& in, const std::string& source) {
  if (in.eof() && !in.bad()) in.clear();  // at the end: nothing left
  const std::streampos pos = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streampos end = in.tellg();
  in.seekg(pos);
  if (pos < 0 || end < 0 || !in) throw IoError(source + ": cannot be read (stream is not seekable)");
  return static_cast<std::uint64_t>(end - pos);
}

void rewind(std::istream& in) {
  in.clear();
  in.seekg(0);
}

/// The whole (remaining) content of a stream.
std::string slurp(std::istream& in, const std::string& source) {
  std::string text(bytesLeft(in, source), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (static_cast<std::size_t>(in.gcount()) != text.size()) throw IoError(source + ": read failed");
  return text;
}

/// Replaces carriage returns, tabs and other blanks by spaces: CGAL's XYZ
/// and OBJ readers only treat ' ' as a separator (a "\r" line is an error,
/// and a tab ends an OBJ face after its first index).
void normalizeBlanks(std::string& text) {
  for (char& c : text) {
    if (c == '\r' || c == '\t' || c == '\v' || c == '\f') c = ' ';
  }
}

/// Silences std::cerr while a CGAL reader runs (some print diagnostics
/// unconditionally) and keeps what they printed for our message. Not safe
/// against other threads writing to std::cerr at the same time.
class CerrCapture {
 public:
  CerrCapture() : previous_(std::cerr.rdbuf(buffer_.rdbuf())) {}
  ~CerrCapture() { std::cerr.rdbuf(previous_); }
  CerrCapture(const CerrCapture&) = delete;
  CerrCapture& operator=(const CerrCapture&) = delete;
  /// The first line CGAL printed.
  std::string firstLine() const {
    const std::string text = buffer_.str();
    return text.substr(0, text.find('\n'));
  }

 private:
  std::ostringstream buffer_;
  std::streambuf* previous_;
};

/// Runs a CGAL reader, turning an allocation failure (a garbled count that
/// CGAL sizes a container with) into a ParseError.
template <class Read>
bool guarded(const std::string& source, Read&& read) {
  try {
    return read();
  } catch (const std::bad_alloc&) {
  } catch (const std::length_error&) {
  }
  parseError(source, "garbled file (it states a size far larger than the file)");
}

/// The number after "line " in a CGAL diagnostic, or 0.
std::size_t lineNumberIn(const std::string& message) {
  const std::size_t at = message.find("line ");
  std::size_t line = 0;
  if (at != std::string::npos) {
    const char* first = message.data() + at + 5;
    std::from_chars(first, message.data() + message.size(), line);
  }
  return line;
}

/// The blank-separated words of a line (views into it).
std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) words.emplace_back(line.substr(start, i - start));
  }
  return words;
}

bool parseCount(std::string_view word, std::uint64_t& value) {
  const char* end = word.data() + word.size();
  const auto result = std::from_chars(word.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

/// Parses a whole word as a finite number (a leading '+' allowed).
bool parseFinite(std::string_view word, double& value) {
  if (word.starts_with('+')) word.remove_prefix(1);
  const char* end = word.data() + word.size();
  const auto result = std::from_chars(word.data(), end, value);
  return result.ec == std::errc() && result.ptr == end && std::isfinite(value);
}

std::uint64_t saturatingMulAdd(std::uint64_t sum, std::uint64_t a, std::uint64_t b) {
  constexpr std::uint64_t kMax = ~std::uint64_t{0};
  if (a != 0 && b > kMax / a) return kMax;
  return sum > kMax - a * b ? kMax : sum + a * b;
}

// ---------------------------------------------------------------------------
// PLY header: parsed here to choose point cloud or mesh, to find normals and
// to check the data is complete before CGAL reads it (CGAL asserts on integer
// coordinates, skips unknown property types and misreads what follows).

enum class PlyData { Ascii, LittleEndian, BigEndian };

struct PlyProperty {
  std::string name;
  std::string type;       ///< value type (of the items, for a list)
  std::string countType;  ///< type of a list's length; empty for a scalar
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;

  const PlyProperty* find(std::string_view property) const {
    for (const PlyProperty& p : properties) {
      if (p.name == property) return &p;
    }
    return nullptr;
  }
};

struct PlyHeader {
  PlyData data = PlyData::Ascii;
  std::vector<PlyElement> elements;
  std::uint64_t dataBytes = 0;  ///< bytes after end_header
  const PlyElement* vertices = nullptr;
  const PlyElement* faces = nullptr;
  bool hasNormals = false;
};

/// Size in bytes of a PLY scalar type, 0 if unknown.
int plyTypeSize(std::string_view type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32") return 4;
  if (type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

bool isPlyFloat(std::string_view type) {
  return type == "float" || type == "float32" || type == "double" || type == "float64";
}

/// Reads one header line (without "\n" or "\r"); false at the end of the
/// stream. Bounded, so that a binary file is not read whole as one line.
bool readHeaderLine(std::istream& in, std::string& line, const std::string& source) {
  constexpr std::size_t kMaxLine = 4096;
  line.clear();
  char c = 0;
  bool any = false;
  while (in.get(c)) {
    any = true;
    if (c == '\n') break;
    if (line.size() == kMaxLine) parseError(source, "garbled PLY header (a header line is too long)");
    line.push_back(c);
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return any;
}

PlyHeader parsePlyHeader(std::istream& in, const std::string& source) {
  PlyHeader header;
  std::string line;
  if (!readHeaderLine(in, line, source) || line.find_first_not_of(" \t") == std::string::npos ||
      splitWords(line).size() != 1 || splitWords(line)[0] != "ply") {
    parseError(source, "not a PLY file (the first line must be \"ply\")");
  }
  readHeaderLine(in, line, source);
  const std::vector<std::string_view> format = splitWords(line);
  if (format.size() != 3 || format[0] != "format" ||
      (format[1] != "ascii" && format[1] != "binary_little_endian" &&
       format[1] != "binary_big_endian")) {
    parseError(source,
               "garbled PLY header (the second line must be \"format ascii|binary_little_endian|"
               "binary_big_endian 1.0\")");
  }
  header.data = format[1] == "ascii"                  ? PlyData::Ascii
                : format[1] == "binary_little_endian" ? PlyData::LittleEndian
                                                      : PlyData::BigEndian;
  bool ended = false;
  while (readHeaderLine(in, line, source)) {
    const std::vector<std::string_view> words = splitWords(line);
    if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
    if (words[0] == "end_header") {
      ended = true;
      break;
    }
    if (words[0] == "element") {
      std::uint64_t count = 0;
      if (words.size() != 3 || !parseCount(words[2], count)) {
        parseError(source, "garbled PLY header line \"" + line + "\"");
      }
      header.elements.push_back({std::string(words[1]), count, {}});
    } else if (words[0] == "property") {
      if (header.elements.empty()) parseError(source, "garbled PLY header (property before element)");
      PlyProperty property;
      if (words.size() == 5 && words[1] == "list") {
        property = {std::string(words[4]), std::string(words[3]), std::string(words[2])};
        const bool integralCount = plyTypeSize(words[2]) != 0 && !isPlyFloat(words[2]) &&
                                   plyTypeSize(words[2]) <= 4;
        if (!integralCount || plyTypeSize(words[3]) == 0) {
          parseError(source, "unsupported PLY list type in \"" + line + "\"");
        }
      } else if (words.size() == 3) {
        property = {std::string(words[2]), std::string(words[1]), ""};
        if (plyTypeSize(words[1]) == 0) {
          parseError(source, "unsupported PLY property type \"" + property.type + "\" in \"" + line + "\"");
        }
      } else {
        parseError(source, "garbled PLY header line \"" + line + "\"");
      }
      header.elements.back().properties.push_back(property);
    } else {
      parseError(source, "garbled PLY header line \"" + line.substr(0, 60) + "\"");
    }
  }
  if (!ended) parseError(source, "garbled or truncated PLY header (no end_header line)");
  header.dataBytes = bytesLeft(in, source);

  for (const PlyElement& element : header.elements) {
    if (!header.vertices && (element.name == "vertex" || element.name == "vertices")) {
      header.vertices = &element;
    }
    if (!header.faces && (element.name == "face" || element.name == "faces")) header.faces = &element;
  }
  if (!header.vertices) parseError(source, "PLY file has no vertex element");
  for (const char* axis : {"x", "y", "z"}) {
    const PlyProperty* p = header.vertices->find(axis);
    if (!p) parseError(source, std::string("PLY vertices have no \"") + axis + "\" property");
    if (!p->countType.empty() || !isPlyFloat(p->type)) {
      parseError(source, std::string("PLY vertex property \"") + axis +
                             "\" must be float or double, not " +
                             (p->countType.empty() ? p->type : "a list"));
    }
  }
  int normalCount = 0;
  for (const char* axis : {"nx", "ny", "nz"}) {
    if (const PlyProperty* p = header.vertices->find(axis)) {
      if (!p->countType.empty() || !isPlyFloat(p->type)) {
        parseError(source, std::string("PLY vertex property \"") + axis +
                               "\" must be float or double");
      }
      ++normalCount;
    }
  }
  if (normalCount != 0 && normalCount != 3) {
    parseError(source, "PLY vertices have only some of the normal properties nx ny nz");
  }
  header.hasNormals = normalCount == 3;
  if (header.faces && header.faces->count > 0) {
    const PlyProperty* indices = header.faces->find("vertex_indices");
    if (!indices) indices = header.faces->find("vertex_index");
    const bool ok = indices && !indices->countType.empty() &&
                    (indices->type == "int" || indices->type == "int32" ||
                     indices->type == "uint" || indices->type == "uint32");
    if (!ok) {
      parseError(source, "PLY faces have no vertex_indices list of int or uint");
    }
  }

  // Minimum size of the data: fixed-size rows are exact, lists count as empty,
  // ASCII values as one digit and a separator.
  std::uint64_t need = 0;
  for (const PlyElement& element : header.elements) {
    std::uint64_t row = 0;
    for (const PlyProperty& p : element.properties) {
      if (header.data == PlyData::Ascii) {
        row += 2;
      } else {
        row += static_cast<std::uint64_t>(plyTypeSize(p.countType.empty() ? p.type : p.countType));
      }
    }
    need = saturatingMulAdd(need, element.count, row);
  }
  if (header.data == PlyData::Ascii && need > 0) --need;
  if (header.dataBytes < need) {
    std::string declared = std::to_string(header.vertices->count) + " vertices";
    if (header.faces) declared += " and " + std::to_string(header.faces->count) + " faces";
    parseError(source, "truncated PLY file: the header declares " + declared +
                           ", which need at least " + std::to_string(need) +
                           " bytes of data, but only " + std::to_string(header.dataBytes) +
                           " bytes follow the header");
  }
  return header;
}

/// Checks every list length in the data against the rest of the file. CGAL
/// sizes a list from its stated length before reading the items, so one
/// garbled length of a list with a wide (or signed) length type exhausts
/// memory. uchar lengths, by far the most common, need no check.
void checkPlyLists(std::istream& in, const PlyHeader& header, const std::string& source) {
  bool risky = false;
  for (const PlyElement& element : header.elements) {
    for (const PlyProperty& p : element.properties) {
      risky = risky || (!p.countType.empty() && p.countType != "uchar" && p.countType != "uint8");
    }
  }
  if (!risky) return;
  auto fail = [&] {
    parseError(source, "PLY data is truncated or garbled (a list is longer than the rest of the file)");
  };
  const bool ascii = header.data == PlyData::Ascii;
  std::uint64_t left = header.dataBytes;
  std::string word;
  auto readLength = [&](const std::string& type) {
    std::uint64_t length = 0;
    if (ascii) {
      if (!(in >> word) || !parseCount(word, length)) fail();
      return length;
    }
    const int size = plyTypeSize(type);
    std::array<unsigned char, 4> b{};
    if (left < static_cast<std::uint64_t>(size) || !in.read(reinterpret_cast<char*>(b.data()), size)) fail();
    left -= static_cast<std::uint64_t>(size);
    for (int i = 0; i < size; ++i) {
      const int byte = header.data == PlyData::BigEndian ? i : size - 1 - i;
      length = (length << 8) | b[static_cast<std::size_t>(byte)];
    }
    const bool isSigned = type == "char" || type == "int8" || type == "short" || type == "int16" ||
                          type == "int" || type == "int32";
    if (isSigned && (length >> (8 * size - 1)) != 0) fail();  // negative
    return length;
  };
  auto skip = [&](std::uint64_t items, int itemSize) {
    if (ascii) {
      if (items > header.dataBytes / 2) fail();
      for (std::uint64_t i = 0; i < items; ++i) {
        if (!(in >> word)) fail();
      }
      return;
    }
    const std::uint64_t bytes = saturatingMulAdd(0, items, static_cast<std::uint64_t>(itemSize));
    if (bytes > left) fail();
    in.ignore(static_cast<std::streamsize>(bytes));
    left -= bytes;
  };
  for (const PlyElement& element : header.elements) {
    for (std::uint64_t row = 0; row < element.count; ++row) {
      for (const PlyProperty& p : element.properties) {
        const std::uint64_t items = p.countType.empty() ? 1 : readLength(p.countType);
        skip(items, plyTypeSize(p.type));
      }
    }
  }
}

std::string plyFormatName(PlyData data) {
  switch (data) {
    case PlyData::Ascii: return "ply-ascii";
    case PlyData::LittleEndian: return "ply-binary-le";
    case PlyData::BigEndian: return "ply-binary-be";
  }
  return "ply";
}

// ---------------------------------------------------------------------------
// Meshes: checked, consistently oriented, sampled by area.

struct Soup {
  std::vector<IoPoint> points;
  std::vector<Polygon> polygons;
};

/// Newell normal of a polygon (length: twice its area when planar).
IoVector newellNormal(const std::vector<IoPoint>& points, const Polygon& polygon) {
  double nx = 0.0, ny = 0.0, nz = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& a = points[polygon[i]];
    const auto& b = points[polygon[(i + 1) % polygon.size()]];
    nx += (a.y() - b.y()) * (a.z() + b.z());
    ny += (a.z() - b.z()) * (a.x() + b.x());
    nz += (a.x() - b.x()) * (a.y() + b.y());
  }
  return IoVector(nx, ny, nz);
}

/// Connected components of polygons sharing a vertex; returns the component
/// of each polygon.
std::vector<std::size_t> polygonComponents(std::size_t pointCount,
                                           const std::vector<Polygon>& polygons) {
  std::vector<std::size_t> parent(pointCount);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto find = [&](std::size_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const Polygon& polygon : polygons) {
    for (std::size_t i = 1; i < polygon.size(); ++i) parent[find(polygon[i])] = find(polygon[0]);
  }
  std::vector<std::size_t> component(polygons.size());
  for (std::size_t f = 0; f < polygons.size(); ++f) component[f] = find(polygons[f][0]);
  return component;
}

/// Orients the soup consistently where it is orientable, keeping in each
/// connected piece the orientation most of its area had in the file, then
/// flips everything if the enclosed volume is negative.
void orientSoup(std::vector<IoPoint>& points, std::vector<Polygon>& polygons) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<IoVector> before;
  before.reserve(polygons.size());
  for (const Polygon& polygon : polygons) before.push_back(newellNormal(points, polygon));

  PMP::orient_polygon_soup(points, polygons);  // may duplicate non-manifold vertices

  const std::vector<std::size_t> component = polygonComponents(points.size(), polygons);
  std::vector<double> kept(points.size(), 0.0);  // per component root: area kept minus area flipped
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const IoVector after = newellNormal(points, polygons[f]);
    const double length = std::sqrt(after.squared_length());
    if (length > 0.0) kept[component[f]] += (before[f] * after) / length;
  }
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    if (kept[component[f]] < 0.0) std::reverse(polygons[f].begin(), polygons[f].end());
  }

  IoVector centroid = CGAL::NULL_VECTOR;
  for (const IoPoint& p : points) centroid = centroid + (p - CGAL::ORIGIN);
  const IoPoint c = CGAL::ORIGIN + centroid / static_cast<double>(points.size());
  double volume = 0.0;
  for (const Polygon& polygon : polygons) {
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
      volume += CGAL::scalar_product(
          points[polygon[0]] - c,
          CGAL::cross_product(points[polygon[i]] - c, points[polygon[i + 1]] - c));
    }
  }
  if (volume < 0.0) {
    for (Polygon& polygon : polygons) std::reverse(polygon.begin(), polygon.end());
  }
}

/// Checks the soup read from a mesh file and samples `count` points on it,
/// uniformly by area, each with its face's normal.
PointCloud sampleMesh(Soup& soup, const std::string& source, std::size_t count,
                      std::uint64_t seed) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  const std::size_t n = soup.points.size();
  for (std::size_t i = 0; i < n; ++i) {
    const IoPoint& p = soup.points[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
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

  std::vector<IoPoint> points = std::move(soup.points);
  std::vector<Polygon> polygons = std::move(soup.polygons);
  PMP::merge_duplicate_points_in_polygon_soup(points, polygons);
  // Drops repeated corners and faces that are not proper polygons; they
  // carry no area, and the orientation needs simple polygons.
  std::erase_if(polygons, [](Polygon& polygon) {
    polygon.erase(std::unique(polygon.begin(), polygon.end()), polygon.end());
    while (polygon.size() > 1 && polygon.front() == polygon.back()) polygon.pop_back();
    Polygon sorted = polygon;
    std::sort(sorted.begin(), sorted.end());
    return polygon.size() < 3 || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
  });
  if (polygons.empty()) parseError(source, "mesh has zero area (every face is degenerate)");
  orientSoup(points, polygons);

  // Fan triangles with their cumulative areas.
  struct Triangle {
    Vec3 a, b, c, normal;
  };
  std::vector<Triangle> triangles;
  std::vector<double> cumulative;
  double total = 0.0;
  auto vec = [&](std::size_t i) { return Vec3(points[i].x(), points[i].y(), points[i].z()); };
  for (const Polygon& polygon : polygons) {
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
      const Vec3 a = vec(polygon[0]), b = vec(polygon[i]), c = vec(polygon[i + 1]);
      const Vec3 cross = (b - a).cross(c - a);
      const double area = 0.5 * cross.norm();
      if (!(area > 0.0) || !std::isfinite(area)) continue;
      triangles.push_back({a, b, c, cross / (2.0 * area)});
      total += area;
      cumulative.push_back(total);
    }
  }
  if (triangles.empty() || !(total > 0.0) || !std::isfinite(total)) {
    parseError(source, "mesh has zero area");
  }

  std::mt19937_64 rng(seed);
  auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };  // [0, 1)
  PointCloud cloud;
  cloud.points.reserve(count);
  cloud.normals.reserve(count);
  for (std::size_t s = 0; s < count; ++s) {
    const double u = uniform() * total;
    const std::size_t t = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), u) -
                                 cumulative.begin()),
        triangles.size() - 1);
    const double r1 = std::sqrt(uniform());
    const double r2 = uniform();
    const Triangle& tri = triangles[t];
    cloud.points.push_back((1.0 - r1) * tri.a + r1 * (1.0 - r2) * tri.b + r1 * r2 * tri.c);
    cloud.normals.push_back(tri.normal);
  }
  return cloud;
}

// ---------------------------------------------------------------------------
// Point clouds.

struct RawCloud {
  std::vector<PointNormal> rows;
  bool hasNormals = false;
};

/// Checks coordinates and normals and turns rows into a PointCloud with unit
/// normals (or none).
PointCloud toPointCloud(const RawCloud& raw, const std::string& source) {
  PointCloud cloud;
  cloud.points.reserve(raw.rows.size());
  if (raw.hasNormals) cloud.normals.reserve(raw.rows.size());
  for (std::size_t i = 0; i < raw.rows.size(); ++i) {
    const IoPoint& p = raw.rows[i].first;
    const Vec3 point(p.x(), p.y(), p.z());
    if (!point.allFinite()) {
      parseError(source, "point " + std::to_string(i + 1) + " has a non-finite coordinate");
    }
    cloud.points.push_back(point);
    if (raw.hasNormals) {
      const IoVector& n = raw.rows[i].second;
      const Vec3 normal(n.x(), n.y(), n.z());
      if (!normal.allFinite()) {
        parseError(source, "point " + std::to_string(i + 1) + " has a non-finite normal");
      }
      const double length = normal.norm();
      if (!(length > 1e-12)) {
        parseError(source, "point " + std::to_string(i + 1) +
                               " has a zero-length (or missing) normal");
      }
      cloud.normals.push_back(normal / length);
    }
  }
  return cloud;
}

RawCloud readPlyPoints(std::istream& in, const PlyHeader& header, const std::string& source) {
  RawCloud raw;
  raw.hasNormals = header.hasNormals;
  raw.rows.reserve(static_cast<std::size_t>(header.vertices->count));
  rewind(in);
  bool ok = false;
  {
    CerrCapture quiet;
    // (CGAL takes the property handlers as rvalues only.)
    const CGAL::First_of_pair_property_map<PointNormal> pointMap;
    const CGAL::Second_of_pair_property_map<PointNormal> normalMap;
    ok = guarded(source, [&] {
      if (raw.hasNormals) {
        return CGAL::IO::read_PLY_with_properties(in, std::back_inserter(raw.rows),
                                                  CGAL::IO::make_ply_point_reader(pointMap),
                                                  CGAL::IO::make_ply_normal_reader(normalMap));
      }
      return CGAL::IO::read_PLY_with_properties(in, std::back_inserter(raw.rows),
                                                CGAL::IO::make_ply_point_reader(pointMap));
    });
  }
  if (raw.rows.size() != header.vertices->count) {
    parseError(source,
               "PLY vertex data is truncated or holds a value that is not a finite number (read " +
                   std::to_string(raw.rows.size()) + " of " +
                   std::to_string(header.vertices->count) + " vertices)");
  }
  if (!ok) parseError(source, "PLY data after the vertices is truncated or unreadable");
  return raw;
}

RawCloud readXyz(std::istream& in, const std::string& source, bool& sixColumns) {
  std::string text = slurp(in, source);
  normalizeBlanks(text);
  // The first data line decides whether the file has normals (CGAL gives a
  // zero normal to every line without one).
  int columns = 0;
  std::size_t pos = 0;
  for (std::size_t lineNumber = 1; columns == 0 && pos < text.size(); ++lineNumber) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::vector<std::string_view> words =
        splitWords(std::string_view(text.data() + pos, end - pos));
    pos = end + 1;
    if (words.empty() || words[0][0] == '#') continue;
    if (lineNumber == 1 && words.size() == 1) continue;  // optional point count
    if (words.size() != 3 && words.size() != 6) {
      parseError(source, "line " + std::to_string(lineNumber) + " has " +
                             std::to_string(words.size()) +
                             " values; expected 3 (x y z) or 6 (x y z nx ny nz)");
    }
    // CGAL would take a bad first line that starts with an integer for
    // the optional point count and skip it.
    for (std::string_view word : words) {
      double value = 0.0;
      if (!parseFinite(word, value)) {
        parseError(source, "line " + std::to_string(lineNumber) +
                               " is not \"x y z\" or \"x y z nx ny nz\" in finite numbers");
      }
    }
    columns = static_cast<int>(words.size());
  }
  sixColumns = columns == 6;
  RawCloud raw;
  raw.hasNormals = sixColumns;
  std::istringstream stream(std::move(text));
  CerrCapture captured;
  const bool ok = CGAL::IO::read_XYZ<PointNormal>(
      stream, std::back_inserter(raw.rows),
      CGAL::parameters::point_map(CGAL::First_of_pair_property_map<PointNormal>())
          .normal_map(CGAL::Second_of_pair_property_map<PointNormal>()));
  if (!ok) {
    const std::size_t line = lineNumberIn(captured.firstLine());
    parseError(source, (line > 0 ? "line " + std::to_string(line) : std::string("a line")) +
                           " is not \"x y z\" or \"x y z nx ny nz\" in finite numbers");
  }
  return raw;
}

// ---------------------------------------------------------------------------
// Mesh files.

Soup readPlyMesh(std::istream& in, const PlyHeader& header, const std::string& source) {
  Soup soup;
  rewind(in);
  bool ok = false;
  {
    CerrCapture quiet;
    ok = guarded(source, [&] {
      return CGAL::IO::read_PLY(in, soup.points, soup.polygons, CGAL::parameters::verbose(false));
    });
  }
  if (!ok || soup.points.size() != header.vertices->count ||
      soup.polygons.size() != header.faces->count) {
    parseError(source, "PLY mesh data is truncated or unreadable (read " +
                           std::to_string(soup.points.size()) + " of " +
                           std::to_string(header.vertices->count) + " vertices and " +
                           std::to_string(soup.polygons.size()) + " of " +
                           std::to_string(header.faces->count) + " faces)");
  }
  return soup;
}

/// Reads an ASCII OFF mesh. Written by hand because CGAL's OFF reader
/// allocates whatever vertex, face and per-face counts the file states
/// before reading them, so one garbled count exhausts memory.
Soup readOff(std::istream& in, const std::string& source) {
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
  if (variant.find('n') != std::string_view::npos) parseError(source, "nOFF files are not supported");
  if (words.size() > 1 && words[1] == "BINARY") {
    parseError(source, "binary OFF is not supported (convert it to ASCII OFF or PLY)");
  }
  const bool homogeneous = variant.find('4') != std::string_view::npos;
  if (words.size() == 1 && !nextLine()) parseError(source, "truncated OFF header");
  const std::size_t first = words[0].ends_with("OFF") ? 1 : 0;  // counts may share the keyword's line
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

  Soup soup;
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

Soup readObj(std::istream& in, const std::string& source) {
  std::string text = slurp(in, source);
  normalizeBlanks(text);
  if (!text.empty() && text.back() != '\n') text.push_back('\n');  // so a bad last line is found
  std::istringstream stream(text);
  Soup soup;
  bool ok = false;
  {
    CerrCapture quiet;
    ok = guarded(source, [&] {
      return CGAL::IO::read_OBJ(stream, soup.points, soup.polygons, CGAL::parameters::verbose(false));
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
    if (soup.points.empty()) parseError(source, "OBJ file has no vertices");
    if (soup.polygons.empty()) parseError(source, "mesh has no faces");
    parseError(source, "an OBJ face refers to a vertex that does not exist");
  }
  return soup;
}

Soup readStl(std::istream& in, const std::string& source, bool& binary) {
  const std::uint64_t size = bytesLeft(in, source);
  std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(size, 4096)), '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  rewind(in);
  std::uint64_t declared = 0;
  if (size >= 84) {
    for (int i = 0; i < 4; ++i) {
      declared |= std::uint64_t{static_cast<unsigned char>(head[80 + i])} << (8 * i);
    }
  }
  binary = size >= 84 && size == 84 + 50 * declared;
  const std::size_t first = head.find_first_not_of(" \t\r\n");
  const bool text = std::none_of(head.begin(), head.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u < 9 || (u > 13 && u < 32);
  });
  const bool ascii = !binary && text && first != std::string::npos &&
                     head.compare(first, 5, "solid") == 0;
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
    rewind(in);
  }
  Soup soup;
  std::vector<std::array<std::size_t, 3>> triangles;
  bool ok = false;
  {
    CerrCapture quiet;
    ok = guarded(source, [&] {
      return CGAL::IO::read_STL(in, soup.points, triangles, CGAL::parameters::verbose(false));
    });
  }
  if (!ok || (binary && triangles.size() != declared)) {
    parseError(source, binary ? "binary STL data is unreadable"
                              : "ASCII STL is truncated or garbled (a facet without 3 vertices, a "
                                "value that is not a finite number, or no endsolid)");
  }
  if (triangles.empty()) parseError(source, "mesh has no faces");
  soup.polygons.reserve(triangles.size());
  for (const auto& t : triangles) soup.polygons.push_back({t[0], t[1], t[2]});
  return soup;
}

}  // namespace

ScanFileType scanFileTypeFromPath(const std::filesystem::path& path) {
  const std::string ext = lowerExtension(path);
  if (ext == "ply") return ScanFileType::Ply;
  if (ext == "xyz" || ext == "xyzn") return ScanFileType::Xyz;
  if (ext == "off") return ScanFileType::Off;
  if (ext == "obj") return ScanFileType::Obj;
  if (ext == "stl") return ScanFileType::Stl;
  throw IoError(path.string() + ": unsupported scan file extension \"" +
                path.extension().string() + "\" (expected .ply, .xyz, .xyzn, .off, .obj or .stl)");
}

Scan readScan(std::istream& in, ScanFileType type, const std::string& source,
              const ReadOptions& options) {
  if (options.normalNeighbors < 6) {
    throw std::invalid_argument("ReadOptions::normalNeighbors must be at least 6");
  }
  if (!in) throw IoError(source + ": cannot be read");
  rewind(in);
  if (bytesLeft(in, source) == 0) parseError(source, "file is empty");

  Scan scan;
  std::optional<Soup> soup;
  RawCloud raw;
  switch (type) {
    case ScanFileType::Ply: {
      const PlyHeader header = parsePlyHeader(in, source);
      checkPlyLists(in, header, source);
      scan.info.format = plyFormatName(header.data);
      if (header.faces && header.faces->count > 0) {
        soup = readPlyMesh(in, header, source);
        scan.info.format += "-mesh";
      } else {
        raw = readPlyPoints(in, header, source);
      }
      break;
    }
    case ScanFileType::Xyz: {
      bool sixColumns = false;
      raw = readXyz(in, source, sixColumns);
      scan.info.format = sixColumns ? "xyzn" : "xyz";
      break;
    }
    case ScanFileType::Off:
      soup = readOff(in, source);
      scan.info.format = "off-mesh";
      break;
    case ScanFileType::Obj:
      soup = readObj(in, source);
      scan.info.format = "obj-mesh";
      break;
    case ScanFileType::Stl: {
      bool binary = false;
      soup = readStl(in, source, binary);
      scan.info.format = binary ? "stl-binary-mesh" : "stl-ascii-mesh";
      break;
    }
  }

  if (soup) {
    if (options.meshSamples < options.minPoints) {
      throw std::invalid_argument("ReadOptions::meshSamples (" +
                                  std::to_string(options.meshSamples) +
                                  ") is smaller than minPoints (" +
                                  std::to_string(options.minPoints) + ")");
    }
    scan.info.fromMesh = true;
    scan.info.meshFaces = soup->polygons.size();
    scan.info.pointsRead = soup->points.size();
    scan.cloud = sampleMesh(*soup, source, options.meshSamples, options.seed);
    return scan;
  }

  scan.info.pointsRead = raw.rows.size();
  scan.cloud = toPointCloud(raw, source);
  const std::size_t n = scan.cloud.size();
  if (n < options.minPoints || n == 0) {
    parseError(source, "has " + std::to_string(n) + " points; at least " +
                           std::to_string(std::max<std::size_t>(options.minPoints, 1)) +
                           " are needed");
  }
  if (!raw.hasNormals) {
    if (n <= static_cast<std::size_t>(options.normalNeighbors)) {
      parseError(source, "has only " + std::to_string(n) +
                             " points, too few to estimate normals from " +
                             std::to_string(options.normalNeighbors) + " neighbours");
    }
    estimateNormals(scan.cloud, options.normalNeighbors);
    scan.info.normalsEstimated = true;
  }
  return scan;
}

Scan readScan(const std::filesystem::path& path, const ReadOptions& options) {
  requireReadableFile(path);
  const ScanFileType type = scanFileTypeFromPath(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot be opened for reading");
  return readScan(in, type, path.string(), options);
}

}  // namespace csgvox
