#pragma once
/// Points sampled on the faces of a mesh read from a file: the faces are
/// oriented consistently and outwards, then sampled uniformly by area.

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/point_cloud.h"
#include "io/mesh_readers.h"

namespace csgvox::detail {

/// Samples `count` points on the faces of `soup` (as readPolygonSoup checked
/// it), uniformly by area, each with the unit normal of its face. Duplicate
/// vertices are merged and degenerate faces dropped; the faces are oriented
/// consistently where the soup is orientable, each connected piece keeping
/// the orientation most of its area had in the file, then all flipped if the
/// enclosed volume is negative. Polygons are split into fans. Same soup and
/// seed, same points.
/// @throw ParseError "<source>: mesh has zero area" when no face has area.
PointCloud sampleMeshFaces(PolygonSoup soup, const std::string& source, std::size_t count,
                           std::uint64_t seed);

}  // namespace csgvox::detail
