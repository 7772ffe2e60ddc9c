#include "io/point_readers.h"

#include <CGAL/IO/PLY.h>
#include <CGAL/IO/read_ply_points.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <istream>
#include <iterator>
#include <limits>
#include <string_view>
#include <utility>
#include <vector>

#include "io/reader_support.h"

namespace csgvox::detail {
namespace {

using IoKernel = CGAL::Simple_cartesian<double>;
using PointNormal = std::pair<IoKernel::Point_3, IoKernel::Vector_3>;

/// Appends a point (and its normal, when given) to `cloud` after checking
/// it; `kind` and `number` name the point in messages ("point 7", "line 9"),
/// built only for a message.
void addPoint(PointCloud& cloud, const Vec3& point, const Vec3* normal, const std::string& source,
              std::string_view kind, std::size_t number) {
  const auto fail = [&](const char* problem) {
    parseError(source, std::string(kind) + " " + std::to_string(number) + problem);
  };
  if (!point.allFinite()) fail(" has a non-finite coordinate");
  cloud.points.push_back(point);
  if (!normal) return;
  if (!normal->allFinite()) fail(" has a non-finite normal");
  const double length = normal->norm();
  if (!(length > 1e-12)) fail(" has a zero-length (or missing) normal");
  cloud.normals.push_back(*normal / length);
}

// A binary PLY whose elements all have rows of fixed size (no lists; a
// point cloud's usual layout): the vertex rows are read in one block and
// x y z (nx ny nz) taken at their offsets, converted as CGAL's reader
// converts them, in a fraction of its time (0.9 s of a 1M-point scan's
// reading). False, with nothing read, for any other layout.
bool readFixedRows(std::istream& in, const PlyHeader& header, const std::string& source,
                   PointCloud& cloud) {
  if (header.data == PlyData::Ascii) return false;
  std::uint64_t skip = 0;
  for (const PlyElement& element : header.elements) {
    std::uint64_t row = 0;
    for (const PlyProperty& p : element.properties) {
      if (!p.countType.empty() || plyTypeSize(p.type) == 0) return false;
      row += std::uint64_t(plyTypeSize(p.type));
    }
    if (&element == header.vertices) break;
    skip += element.count * row;
  }
  const PlyElement& vertices = *header.vertices;
  // Offset and size of a property in a vertex row (size 0: absent).
  struct Field {
    std::size_t offset = 0;
    int size = 0;
  };
  std::size_t stride = 0;
  for (const PlyProperty& p : vertices.properties) stride += std::size_t(plyTypeSize(p.type));
  const auto field = [&](std::string_view name) {
    Field f;
    std::size_t at = 0;
    for (const PlyProperty& p : vertices.properties) {
      if (p.name == name) f = {at, plyTypeSize(p.type)};
      at += std::size_t(plyTypeSize(p.type));
    }
    return f;
  };
  const std::array<Field, 6> fields = {field("x"),  field("y"),  field("z"),
                                       field("nx"), field("ny"), field("nz")};
  const std::size_t count = std::size_t(vertices.count);
  if (stride == 0 || count > std::numeric_limits<std::size_t>::max() / stride) return false;
  // The data are the file's last dataBytes bytes.
  in.clear();
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (!in || size < std::streamoff(header.dataBytes)) return false;
  in.seekg(size - std::streamoff(header.dataBytes) + std::streamoff(skip));
  if (!in) return false;
  std::vector<char> block(count * stride);
  in.read(block.data(), std::streamsize(block.size()));
  if (std::size_t(in.gcount()) != block.size()) {
    parseError(source, "PLY vertex data is truncated (read " +
                           std::to_string(std::size_t(in.gcount()) / stride) + " of " +
                           std::to_string(count) + " vertices)");
  }
  const bool swap = header.data == PlyData::BigEndian;
  const auto value = [&](const char* row, const Field& f) {
    std::array<char, 8> bytes{};
    std::memcpy(bytes.data(), row + f.offset, std::size_t(f.size));
    if (swap) std::reverse(bytes.begin(), bytes.begin() + f.size);
    if (f.size == 4) {
      float v;
      std::memcpy(&v, bytes.data(), 4);
      return double(v);
    }
    double v;
    std::memcpy(&v, bytes.data(), 8);
    return v;
  };
  cloud.points.reserve(count);
  if (header.hasNormals) cloud.normals.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const char* row = block.data() + i * stride;
    const Vec3 p(value(row, fields[0]), value(row, fields[1]), value(row, fields[2]));
    Vec3 n = Vec3::Zero();
    if (header.hasNormals)
      n = {value(row, fields[3]), value(row, fields[4]), value(row, fields[5])};
    addPoint(cloud, p, header.hasNormals ? &n : nullptr, source, "point", i + 1);
  }
  return true;
}

}  // namespace

PointCloud readPlyPoints(std::istream& in, const PlyHeader& header, const std::string& source) {
  if (PointCloud cloud; readFixedRows(in, header, source, cloud)) return cloud;
  std::vector<PointNormal> rows;
  rows.reserve(static_cast<std::size_t>(header.vertices->count));
  rewindStream(in);
  bool ok = false;
  {
    CerrCapture quiet;
    // (CGAL takes the property handlers as rvalues only.)
    const CGAL::First_of_pair_property_map<PointNormal> pointMap;
    const CGAL::Second_of_pair_property_map<PointNormal> normalMap;
    ok = guarded(source, [&] {
      if (header.hasNormals) {
        return CGAL::IO::read_PLY_with_properties(in, std::back_inserter(rows),
                                                  CGAL::IO::make_ply_point_reader(pointMap),
                                                  CGAL::IO::make_ply_normal_reader(normalMap));
      }
      return CGAL::IO::read_PLY_with_properties(in, std::back_inserter(rows),
                                                CGAL::IO::make_ply_point_reader(pointMap));
    });
  }
  if (rows.size() != header.vertices->count) {
    parseError(source,
               "PLY vertex data is truncated or holds a value that is not a finite number (read " +
                   std::to_string(rows.size()) + " of " + std::to_string(header.vertices->count) +
                   " vertices)");
  }
  if (!ok) parseError(source, "PLY data after the vertices is truncated or unreadable");

  PointCloud cloud;
  cloud.points.reserve(rows.size());
  if (header.hasNormals) cloud.normals.reserve(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& [p, n] = rows[i];
    const Vec3 normal(n.x(), n.y(), n.z());
    addPoint(cloud, Vec3(p.x(), p.y(), p.z()), header.hasNormals ? &normal : nullptr, source,
             "point", i + 1);
  }
  return cloud;
}

PointCloud readXyzPoints(std::istream& in, const std::string& source) {
  std::string text = slurp(in, source);
  normalizeBlanks(text);
  PointCloud cloud;
  std::size_t columns = 0;      // of the first data line: 3 or 6
  std::size_t columnsLine = 0;  // that line's number
  std::size_t pos = 0;
  for (std::size_t lineNumber = 1; pos < text.size(); ++lineNumber) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::vector<std::string_view> words =
        splitWords(std::string_view(text.data() + pos, end - pos));
    pos = end + 1;
    if (words.empty() || words[0][0] == '#') continue;
    const std::string where = "line " + std::to_string(lineNumber);
    std::uint64_t count = 0;
    if (lineNumber == 1 && words.size() == 1 && parseCount(words[0], count))
      continue;  // point count
    if (words.size() != 3 && words.size() != 6) {
      parseError(source, where + " has " + std::to_string(words.size()) +
                             " values; expected 3 (x y z) or 6 (x y z nx ny nz)");
    }
    if (columns == 0) {
      columns = words.size();
      columnsLine = lineNumber;
    } else if (words.size() != columns) {
      parseError(source, where + " has " + std::to_string(words.size()) + " values but line " +
                             std::to_string(columnsLine) + " has " + std::to_string(columns) +
                             "; every line must have the same columns (x y z, or x y z nx ny nz)");
    }
    double v[6] = {};
    for (std::size_t i = 0; i < words.size(); ++i) {
      if (!parseFinite(words[i], v[i])) {
        parseError(source, where + ": \"" + std::string(words[i].substr(0, 40)) +
                               "\" is not a finite number");
      }
    }
    const Vec3 normal(v[3], v[4], v[5]);
    addPoint(cloud, Vec3(v[0], v[1], v[2]), columns == 6 ? &normal : nullptr, source, "line",
             lineNumber);
  }
  return cloud;
}

}  // namespace csgvox::detail
