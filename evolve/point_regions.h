#pragma once
/// Regions of points: the points of a set grouped by proximity, so that the
/// places where a tree explains the scan badly can be worked on one by one.

#include <cstdint>
#include <span>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// Groups `subset` (indices into `points`) into regions: a grid of cubic
/// cells of side `cell` is laid over the points, and points in the same or
/// in face-, edge- or corner-neighbouring occupied cells are in one region
/// (transitively). Each region lists its indices ascending; regions are
/// ordered by their first index. Deterministic.
/// @throw std::invalid_argument when cell is not > 0 or an index is out of range.
std::vector<std::vector<std::uint32_t>> pointRegions(std::span<const Vec3> points,
                                                     std::span<const std::uint32_t> subset,
                                                     double cell);

}  // namespace csgvox
