#pragma once
/// Scans given as arrays in memory (points, and normals or none) instead of
/// files: checked as the file readers check them, with missing normals
/// estimated as readScan() estimates them.

#include <string>
#include <vector>

#include "core/geometry.h"
#include "io/scan_reader.h"

namespace csgvox {

/// Estimates the normals of a point cloud read without them (nothing to do
/// for a scan with normals or sampled from a mesh), as readScan() does, and
/// sets info.normalsEstimated.
/// @throw ParseError "<source>: ..." when the points are too few for
///        options.normalNeighbors neighbours or span no surface.
void completeNormals(Scan& scan, const std::string& source, const ReadOptions& options = {});

/// A scan from arrays: `normals` empty (estimated) or one per point (unit
/// length after scaling; normals within 1e-9 of unit length are kept as
/// given, so a scan's own normals pass unchanged). info.format is "array".
/// @throw ParseError "<source>: ..." for a non-finite coordinate or normal, a
///        zero-length normal, a normal count that is neither 0 nor the point
///        count, fewer than options.minPoints points, or normals that cannot
///        be estimated.
Scan scanFromArrays(std::vector<Vec3> points, std::vector<Vec3> normals,
                    const std::string& source = "<array>", const ReadOptions& options = {});

}  // namespace csgvox
