#pragma once
/// What every scan-format fuzz target does with its input: read it as a
/// scan (a point cloud, or a mesh sampled by area) and, for mesh formats, as
/// a mesh. Bad input must end in ParseError or IoError; anything else (a
/// crash, another exception, a sanitizer report, a hang) is a bug.

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "io/errors.h"
#include "io/mesh_files.h"
#include "io/scan_content.h"

namespace csgvox::fuzz {

/// The fuzzer's bytes as a string.
inline std::string bytes(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// Reads `content` as a scan of `type` and, unless it is XYZ, as a mesh.
inline void readAsScanAndMesh(const std::string& content, ScanFileType type) {
  ReadOptions options;
  options.meshSamples = 64;  // the sampling is exercised, not measured
  options.minPoints = 1;
  try {
    std::istringstream in(content, std::ios::binary);
    readScanContent(in, type, "fuzz-input", options);
  } catch (const ParseError&) {
  } catch (const IoError&) {
  }
  if (type == ScanFileType::Xyz) return;
  try {
    std::istringstream in(content, std::ios::binary);
    readMesh(in, type, "fuzz-input");
  } catch (const ParseError&) {
  } catch (const IoError&) {
  }
}

}  // namespace csgvox::fuzz
