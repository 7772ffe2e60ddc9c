#include "io/scan_reader.h"

#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <string>

#include "io/errors.h"
#include "io/file_util.h"
#include "io/point_arrays.h"
#include "io/scan_content.h"

namespace csgvox {

Scan readScan(std::istream& in, ScanFileType type, const std::string& source,
              const ReadOptions& options) {
  checkReadOptions(options);
  Scan scan = readScanContent(in, type, source, options);
  completeNormals(scan, source, options);
  return scan;
}

namespace {

// The file opened for reading, after the checks every scan file passes.
std::ifstream openScanFile(const std::filesystem::path& path) {
  requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot be opened for reading");
  return in;
}

}  // namespace

Scan readScan(const std::filesystem::path& path, const ReadOptions& options) {
  std::ifstream in = openScanFile(path);
  const ScanFileType type = scanFileTypeFromPath(path);
  return readScan(in, type, path.string(), options);
}

Scan readScans(const std::vector<std::filesystem::path>& paths, const ReadOptions& options) {
  if (paths.empty()) throw std::invalid_argument("readScans: no file given");
  if (paths.size() == 1) return readScan(paths.front(), options);
  checkReadOptions(options);
  ReadOptions each = options;
  each.minPoints = 1;  // a view may be small; the whole must not
  Scan all;
  bool normals = true;
  std::vector<PointCloud> clouds;
  for (const std::filesystem::path& path : paths) {
    std::ifstream in = openScanFile(path);
    const ScanFileType type = scanFileTypeFromPath(path);
    Scan one = readScanContent(in, type, path.string(), each);
    if (one.info.fromMesh) {
      throw ParseError(path.string() +
                       ": is a mesh; only point clouds (views of one part) can be read together");
    }
    if (all.info.format.empty()) all.info.format = one.info.format;
    all.info.pointsRead += one.info.pointsRead;
    all.info.files.push_back(path.string());
    normals = normals && one.cloud.hasNormals();
    clouds.push_back(std::move(one.cloud));
  }
  for (PointCloud& c : clouds) {
    all.cloud.points.insert(all.cloud.points.end(), c.points.begin(), c.points.end());
    if (normals) all.cloud.normals.insert(all.cloud.normals.end(), c.normals.begin(), c.normals.end());
  }
  const std::string source = paths.front().string() + " and " + std::to_string(paths.size() - 1) +
                             (paths.size() == 2 ? " other file" : " other files");
  const std::size_t minimum = std::max<std::size_t>(options.minPoints, 1);
  if (all.cloud.size() < minimum) {
    throw ParseError(source + ": have " + std::to_string(all.cloud.size()) + " points; at least " +
                     std::to_string(minimum) + " are needed");
  }
  completeNormals(all, source, options);
  return all;
}

}  // namespace csgvox
