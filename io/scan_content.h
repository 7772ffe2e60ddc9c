#pragma once
/// The points of a scan file as the file holds them: the format decoded,
/// meshes sampled, but missing normals left missing (readScan estimates
/// them).

#include <iosfwd>
#include <string>

#include "io/scan_reader.h"

namespace csgvox {

/// Reads a scan of the given type from a seekable stream opened in binary
/// mode, from position 0 to its end, as readScan(in, type, source, options)
/// does but without estimating normals: a point cloud without normals comes
/// back with an empty `cloud.normals` (and info.normalsEstimated false).
/// options.normalNeighbors is not used.
/// @throw ParseError "<source>: ..." for invalid content (as readScan).
/// @throw IoError when the stream cannot be read or is not seekable.
/// @throw std::invalid_argument when meshSamples < minPoints for a mesh.
Scan readScanContent(std::istream& in, ScanFileType type, const std::string& source,
                     const ReadOptions& options = {});

}  // namespace csgvox
