#include "io/scan_reader.h"

#include <fstream>
#include <stdexcept>
#include <string>

#include "io/errors.h"
#include "io/file_util.h"
#include "io/scan_content.h"
#include "primitives/normal_estimation.h"

namespace csgvox {

Scan readScan(std::istream& in, ScanFileType type, const std::string& source,
              const ReadOptions& options) {
  if (options.normalNeighbors < 6) {
    throw std::invalid_argument("ReadOptions::normalNeighbors must be at least 6");
  }
  Scan scan = readScanContent(in, type, source, options);
  if (scan.info.fromMesh || scan.cloud.hasNormals()) return scan;
  const std::size_t n = scan.cloud.size();
  if (n <= static_cast<std::size_t>(options.normalNeighbors)) {
    throw ParseError(source + ": has only " + std::to_string(n) +
                     " points, too few to estimate normals from " +
                     std::to_string(options.normalNeighbors) + " neighbours");
  }
  try {
    estimateNormals(scan.cloud, options.normalNeighbors);
  } catch (const std::invalid_argument& e) {
    // Points that span no surface (all at one position, on a line).
    throw ParseError(source + ": " + e.what());
  }
  scan.info.normalsEstimated = true;
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
