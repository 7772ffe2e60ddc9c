#pragma once
/// Uniform sampling of the boundary of a CSG solid: synthetic scans with
/// outward normals, optional noise and scanner-like holes.

#include <cstdint>

#include "core/csg_tree.h"
#include "core/point_cloud.h"

namespace csgvox {

/// Options of sampleSurface.
struct SampleOptions {
  std::size_t points = 20000;  ///< number of points returned
  double noise = 0.0;          ///< Gaussian position noise sigma, fraction of the diagonal D
  int dropPatches = 0;         ///< number of round holes cut into the scan
  double patchRadius = 0.05;   ///< radius of each hole, fraction of D
  std::uint64_t seed = 1;      ///< random seed; same seed, same scan
};

/// Result of sampleSurface.
struct SurfaceSample {
  PointCloud cloud;          ///< points on the solid's boundary with unit outward normals
  double surfaceArea = 0.0;  ///< Monte-Carlo estimate of the boundary's area
  double diagonal = 0.0;     ///< D: diagonal of the tree's bounding box
  /// For each point, the index (in tree.leaves() order) of the primitive whose
  /// surface it was sampled on: a ground-truth segmentation of the scan.
  std::vector<std::uint32_t> source;
};

/// Samples points uniformly (by area) on the boundary of the solid. Points
/// lie exactly on a primitive's surface (before noise); the normal is that
/// surface's outward normal as seen from the solid (flipped for subtracted
/// primitives). Internal faces (shared by two operands) are not sampled.
/// D is the diagonal of tree.bounds().
/// @throw std::invalid_argument if the tree is empty, unbounded, or has no
///        boundary to sample.
SurfaceSample sampleSurface(const CsgTree& tree, const SampleOptions& options = {});

}  // namespace csgvox
