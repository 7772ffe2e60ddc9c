#include "io/scan_content.h"

#include <algorithm>
#include <istream>
#include <stdexcept>
#include <utility>

#include "io/errors.h"
#include "io/file_util.h"
#include "io/mesh_readers.h"
#include "io/mesh_sampling.h"
#include "io/ply_header.h"
#include "io/point_readers.h"
#include "io/reader_support.h"

namespace csgvox {

using detail::parseError;

ScanFileType scanFileTypeFromPath(const std::filesystem::path& path) {
  const std::string ext = lowerExtension(path);
  if (ext == "ply") return ScanFileType::Ply;
  if (ext == "xyz" || ext == "xyzn" || ext == "pts" || ext == "txt") return ScanFileType::Xyz;
  if (ext == "off") return ScanFileType::Off;
  if (ext == "obj") return ScanFileType::Obj;
  if (ext == "stl") return ScanFileType::Stl;
  throw IoError(path.string() + ": unsupported scan file extension \"" + path.extension().string() +
                "\" (expected .ply, .xyz, .xyzn, .pts, .txt, .off, .obj or .stl)");
}

Scan readScanContent(std::istream& in, ScanFileType type, const std::string& source,
                     const ReadOptions& options) {
  if (!in) throw IoError(source + ": cannot be read");
  detail::rewindStream(in);
  if (detail::bytesLeft(in, source) == 0) parseError(source, "file is empty");

  Scan scan;
  bool isMesh = type != ScanFileType::Ply && type != ScanFileType::Xyz;
  if (type == ScanFileType::Ply) {
    const detail::PlyHeader header = detail::parsePlyHeader(in, source);
    detail::checkPlyData(in, header, source);
    isMesh = header.faces && header.faces->count > 0;
    if (!isMesh) {
      scan.cloud = detail::readPlyPoints(in, header, source);
      scan.info.format = detail::plyFormatName(header.data);
    }
  } else if (type == ScanFileType::Xyz) {
    scan.cloud = detail::readXyzPoints(in, source);
    scan.info.format = scan.cloud.hasNormals() ? "xyzn" : "xyz";
  }

  if (isMesh) {
    if (options.meshSamples < options.minPoints) {
      throw std::invalid_argument(
          "ReadOptions::meshSamples (" + std::to_string(options.meshSamples) +
          ") is smaller than minPoints (" + std::to_string(options.minPoints) + ")");
    }
    detail::PolygonSoup soup = detail::readPolygonSoup(in, type, source);
    scan.info.format = soup.format;
    scan.info.fromMesh = true;
    scan.info.meshFaces = soup.polygons.size();
    scan.info.pointsRead = soup.points.size();
    scan.cloud =
        detail::sampleMeshFaces(std::move(soup), source, options.meshSamples, options.seed);
    return scan;
  }

  scan.info.pointsRead = scan.cloud.size();
  const std::size_t n = scan.cloud.size();
  if (n < options.minPoints || n == 0) {
    parseError(source, "has " + std::to_string(n) + " points; at least " +
                           std::to_string(std::max<std::size_t>(options.minPoints, 1)) +
                           " are needed");
  }
  return scan;
}

}  // namespace csgvox
