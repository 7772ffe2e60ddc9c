#pragma once
/// Scans given as arrays in memory (points, and normals or none) instead of
/// files: checked as the file readers check them, with missing normals
/// estimated as readScan() estimates them.

#include <string>
#include <vector>

#include "core/geometry.h"
#include "io/scan_reader.h"

namespace csgvox {

/// Checks the options that readScan() and scanFromArrays() take.
/// @throw std::invalid_argument when normalNeighbors < 6 or
///        minNormalAgreement is outside 0..1.
void checkReadOptions(const ReadOptions& options);

/// Removes the outliers of a point cloud (findOutliers; when
/// options.removeOutliers, counted in info.outliersRemoved and
/// offSurfaceRemoved), then estimates the normals of a point cloud read
/// without them, or with normals
/// of which fewer than options.minNormalAgreement agree with the local
/// surface (nothing to do for a scan sampled from a mesh), as readScan()
/// does, and sets info.normalsEstimated, normalsReplaced and
/// normalAgreement.
/// @throw ParseError "<source>: ..." when the points are too few for
///        options.normalNeighbors neighbours, span no surface, or all lie on
///        one plane within their noise.
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
