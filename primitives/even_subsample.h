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
/// the points are binned into cubic cells, and every cell keeps the same
/// number q of its points (all of them where it holds fewer), chosen at
/// random by the seed; q is the largest that keeps at most options.points.
/// Dense regions are thinned, sparse ones kept. Cells are at least
/// options.noiseCells x `noise` wide (scan units), so a noisy surface keeps
/// its noise: a cell narrower than the band would keep the band's tails as
/// often as its middle. All indices when there are no more than
/// options.points points. The same input and seed give the same indices,
/// whatever the number of threads.
/// @throw std::invalid_argument when options.points is 0, options.cellSide is
///        not positive or options.noiseCells or `noise` is negative.
std::vector<std::uint32_t> evenSubsample(std::span<const Vec3> points, double noise,
                                         const SubsampleOptions& options = {});

}  // namespace csgvox
