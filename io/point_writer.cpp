#include "io/point_writer.h"

#include <bit>
#include <charconv>
#include <ostream>
#include <stdexcept>
#include <string>

#include "core/decimal.h"
#include "io/errors.h"
#include "io/file_util.h"

namespace csgvox {
namespace {

void checkNormals(const PointCloud& cloud) {
  if (!cloud.normals.empty() && cloud.normals.size() != cloud.points.size()) {
    throw std::invalid_argument("point cloud has " + std::to_string(cloud.normals.size()) +
                                " normals for " + std::to_string(cloud.points.size()) + " points");
  }
}

// Appends the bytes of a float in the requested byte order.
void appendFloat(std::string& out, float v, bool bigEndian) {
  const auto bits = std::bit_cast<std::uint32_t>(v);
  for (int i = 0; i < 4; ++i) {
    const int shift = bigEndian ? 8 * (3 - i) : 8 * i;
    out.push_back(static_cast<char>((bits >> shift) & 0xFFu));
  }
}

void writePly(std::ostream& out, const PointCloud& cloud, std::span<const Rgb8> colors,
              bool hasColors, PlyEncoding encoding) {
  checkNormals(cloud);
  if (hasColors && colors.size() != cloud.size()) {
    throw std::invalid_argument("point cloud has " + std::to_string(cloud.size()) + " points but " +
                                std::to_string(colors.size()) + " colours");
  }
  const bool hasNormals = cloud.hasNormals();
  const char* format = encoding == PlyEncoding::Ascii                ? "ascii"
                       : encoding == PlyEncoding::BinaryLittleEndian ? "binary_little_endian"
                                                                     : "binary_big_endian";
  out << "ply\nformat " << format << " 1.0\ncomment written by csgvox\n"
      << "element vertex " << cloud.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n";
  if (hasNormals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  if (hasColors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out << "end_header\n";

  const bool bigEndian = encoding == PlyEncoding::BinaryBigEndian;
  std::string chunk;
  constexpr std::size_t kChunkPoints = 4096;
  chunk.reserve(kChunkPoints * 80);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    float values[6];
    int count = 0;
    for (int a = 0; a < 3; ++a) values[count++] = static_cast<float>(cloud.points[i][a]);
    if (hasNormals) {
      for (int a = 0; a < 3; ++a) values[count++] = static_cast<float>(cloud.normals[i][a]);
    }
    if (encoding == PlyEncoding::Ascii) {
      for (int v = 0; v < count; ++v) {
        if (v > 0) chunk.push_back(' ');
        appendDecimal(chunk, values[v]);
      }
      if (hasColors) {
        for (std::uint8_t c : colors[i]) {
          chunk.push_back(' ');
          appendDecimal(chunk, static_cast<unsigned>(c));
        }
      }
      chunk.push_back('\n');
    } else {
      for (int v = 0; v < count; ++v) appendFloat(chunk, values[v], bigEndian);
      if (hasColors) {
        for (std::uint8_t c : colors[i]) chunk.push_back(static_cast<char>(c));
      }
    }
    if ((i + 1) % kChunkPoints == 0) {
      out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
      chunk.clear();
    }
  }
  out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
}

void writeXyz(std::ostream& out, const PointCloud& cloud) {
  checkNormals(cloud);
  const bool hasNormals = cloud.hasNormals();
  std::string chunk;
  constexpr std::size_t kChunkPoints = 4096;
  chunk.reserve(kChunkPoints * 150);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      if (a > 0) chunk.push_back(' ');
      appendDecimal(chunk, cloud.points[i][a]);
    }
    if (hasNormals) {
      for (int a = 0; a < 3; ++a) {
        chunk.push_back(' ');
        appendDecimal(chunk, cloud.normals[i][a]);
      }
    }
    chunk.push_back('\n');
    if ((i + 1) % kChunkPoints == 0) {
      out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
      chunk.clear();
    }
  }
  out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
}

// The stream versions report a failed stream; the file versions leave that to
// writeFileAtomically, whose message names the file.
void requireGood(const std::ostream& out, const char* what) {
  if (!out)
    throw IoError(std::string("writing ") + what + " failed: the output stream is in error");
}

}  // namespace

void writePointCloudPly(std::ostream& out, const PointCloud& cloud, PlyEncoding encoding) {
  writePly(out, cloud, {}, false, encoding);
  requireGood(out, "a PLY point cloud");
}

void writePointCloudPly(const std::filesystem::path& path, const PointCloud& cloud,
                        PlyEncoding encoding) {
  checkNormals(cloud);
  writeFileAtomically(
      path, [&](std::ostream& out) { writePly(out, cloud, {}, false, encoding); },
      encoding != PlyEncoding::Ascii);
}

void writePointCloudPly(std::ostream& out, const PointCloud& cloud, std::span<const Rgb8> colors,
                        PlyEncoding encoding) {
  writePly(out, cloud, colors, true, encoding);
  requireGood(out, "a PLY point cloud");
}

void writePointCloudPly(const std::filesystem::path& path, const PointCloud& cloud,
                        std::span<const Rgb8> colors, PlyEncoding encoding) {
  checkNormals(cloud);
  if (colors.size() != cloud.size()) {
    throw std::invalid_argument(path.string() + ": point cloud has " +
                                std::to_string(cloud.size()) + " points but " +
                                std::to_string(colors.size()) + " colours");
  }
  writeFileAtomically(
      path, [&](std::ostream& out) { writePly(out, cloud, colors, true, encoding); },
      encoding != PlyEncoding::Ascii);
}

void writePointCloudXyz(std::ostream& out, const PointCloud& cloud) {
  writeXyz(out, cloud);
  requireGood(out, "an XYZ point cloud");
}

void writePointCloudXyz(const std::filesystem::path& path, const PointCloud& cloud) {
  checkNormals(cloud);
  writeFileAtomically(path, [&](std::ostream& out) { writeXyz(out, cloud); });
}

}  // namespace csgvox
