#pragma once
/// A spatially even subsample of a large scan, on which surface detection
/// searches: the same number of points whatever the scan's size, so its cost
/// and its thresholds do not follow the density.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// Options of evenSubsample.
struct SubsampleOptions {
  std::size_t points = 100000;  ///< about this many points remain (count, at least 1)
  double cellSide = 0.01;       ///< smallest cell side, fraction of the bounding-box diagonal D
  double noiseCells = 6.0;      ///< the cell side is at least this many times the noise sigma
                                ///< (ratio): each cell then spans the whole noise band
  std::uint64_t seed = 1;       ///< chooses the points kept within each cell
};

/// Indices (ascending) of about options.points of `points`, spread evenly:
/// the points are binned into cubic cells, a cell's density is the largest
/// count among it and its 26 neighbours, and each point is kept with
/// probability min(1, q / density) (drawn from the seed and its index), q
/// chosen so that about options.points remain. Dense regions are thinned to
/// about q points per cell, sparse ones kept. Cells are at least
/// options.noiseCells x `noise` wide (scan units), and a cell holding only
/// the tail of a noise band is thinned as its neighbour holding the middle,
/// so a noisy surface keeps its noise. All indices when there are no more
/// than options.points points. The same input and seed give the same
/// indices, whatever the number of threads.
/// @throw std::invalid_argument when options.points is 0, options.cellSide is
///        not positive or options.noiseCells or `noise` is negative.
std::vector<std::uint32_t> evenSubsample(std::span<const Vec3> points, double noise,
                                         const SubsampleOptions& options = {});

}  // namespace csgvox
