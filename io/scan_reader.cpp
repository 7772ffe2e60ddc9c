#include "io/scan_reader.h"

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

Scan readScan(const std::filesystem::path& path, const ReadOptions& options) {
  requireReadableFile(path);
  const ScanFileType type = scanFileTypeFromPath(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot be opened for reading");
  return readScan(in, type, path.string(), options);
}

}  // namespace csgvox
