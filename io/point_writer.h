#pragma once
/// Writing point clouds as PLY (optionally with per-point colours) and XYZ.

#include <array>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <span>

#include "core/point_cloud.h"

namespace csgvox {

/// Encoding of the data section of a PLY file.
enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

/// An RGB colour, 0-255 per channel.
using Rgb8 = std::array<std::uint8_t, 3>;

/// Writes `cloud` as PLY: a vertex element with float x y z, plus float
/// nx ny nz when the cloud has normals. Coordinates are rounded to float.
/// A binary encoding needs `out` opened in binary mode.
/// @throw std::invalid_argument if the cloud has some but not one normal per point.
/// @throw IoError if the stream fails.
void writePointCloudPly(std::ostream& out, const PointCloud& cloud,
                        PlyEncoding encoding = PlyEncoding::BinaryLittleEndian);

/// Writes `cloud` as a PLY file, replacing `path` atomically.
/// @throw std::invalid_argument as for the stream version.
/// @throw IoError "<path>: ..." when the file cannot be written.
void writePointCloudPly(const std::filesystem::path& path, const PointCloud& cloud,
                        PlyEncoding encoding = PlyEncoding::BinaryLittleEndian);

/// Writes `cloud` as PLY with an extra uchar red green blue colour per point
/// (after the normals), e.g. to show which surface each point belongs to.
/// @throw std::invalid_argument if colors.size() != cloud.size() or the
///        normals do not match the points.
/// @throw IoError if the stream fails.
void writePointCloudPly(std::ostream& out, const PointCloud& cloud, std::span<const Rgb8> colors,
                        PlyEncoding encoding = PlyEncoding::BinaryLittleEndian);

/// Writes a coloured PLY file (see the stream version), replacing `path`
/// atomically.
/// @throw std::invalid_argument as for the stream version.
/// @throw IoError "<path>: ..." when the file cannot be written.
void writePointCloudPly(const std::filesystem::path& path, const PointCloud& cloud,
                        std::span<const Rgb8> colors,
                        PlyEncoding encoding = PlyEncoding::BinaryLittleEndian);

/// Writes `cloud` as text, one point per line: "x y z" or, when the cloud
/// has normals, "x y z nx ny nz". Numbers are written in the shortest form
/// that reads back to the same double.
/// @throw std::invalid_argument if the cloud has some but not one normal per point.
/// @throw IoError if the stream fails.
void writePointCloudXyz(std::ostream& out, const PointCloud& cloud);

/// Writes an XYZ file (see the stream version), replacing `path` atomically.
/// @throw std::invalid_argument as for the stream version.
/// @throw IoError "<path>: ..." when the file cannot be written.
void writePointCloudXyz(const std::filesystem::path& path, const PointCloud& cloud);

}  // namespace csgvox
