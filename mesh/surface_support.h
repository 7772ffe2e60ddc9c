#pragma once
/// How much of a tree's boundary the scan supports: the points only judge a
/// tree where they are, so a surface the tree adds where the scan has no
/// points (a slab carved inside a plate, thinner than a voxel) is invisible
/// to any fitness measured at the points. Sampling the boundary and looking
/// for the nearest scan point sees it.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/csg_tree.h"
#include "core/nearest_neighbors.h"

namespace csgvox {

/// Options of surfaceSupport().
struct SupportOptions {
  double distance = 0.0;         ///< scan units: a boundary point farther from every scan point
                                 ///< is unsupported
  std::size_t samples = 20000;   ///< boundary points sampled
  std::uint64_t seed = 1;        ///< seed of the boundary sampling
  bool keepUnsupported = false;  ///< return the unsupported samples themselves
};

/// A tree's boundary area and the part of it no scan point is near.
struct SurfaceSupport {
  double area = 0.0;         ///< estimated boundary area, scan units²
  double unsupported = 0.0;  ///< estimated area farther than the distance from every scan point
  double sampleArea = 0.0;   ///< boundary area each sample stands for
  std::vector<Vec3> unsupportedSamples;  ///< with keepUnsupported: those samples, in sample order
  std::vector<double> unsupportedDistances;  ///< and each one's distance to the nearest scan point
};

/// Samples the boundary of `tree` uniformly and measures the area whose
/// nearest scan point (in `scan`, a k-d tree of the scan's points) is
/// farther than options.distance.
/// @throw std::invalid_argument when the tree cannot be sampled (empty,
///        unbounded, no boundary) or the scan is empty.
SurfaceSupport surfaceSupport(const CsgTree& tree, const NearestNeighbors& scan,
                              const SupportOptions& options);

}  // namespace csgvox
