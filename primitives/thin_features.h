#pragma once
/// Features of a part thinner than a few voxels, found on its surfaces: a
/// wall or a slot between two opposite-facing parallel planes that face each
/// other, and a rod or a hole of small radius. The voxel stage cannot see
/// them at a coarse resolution; the main job lays a finer grid when one is
/// found (pipeline/detect_and_fit.h).

#include <span>
#include <string_view>
#include <vector>

#include "core/point_cloud.h"
#include "core/surface.h"

namespace csgvox {

/// What makes a feature thin.
enum class ThinKind {
  Wall,  ///< material between two opposite-facing planes (normals pointing apart)
  Slot,  ///< empty space between two opposite-facing planes (normals pointing towards each other)
  Rod,   ///< a convex cylinder
  Hole,  ///< a concave cylinder
};

/// "wall", "slot", "rod" or "hole".
std::string_view thinKindName(ThinKind kind);

/// One thin feature.
struct ThinFeature {
  ThinKind kind = ThinKind::Wall;
  double thickness = 0.0;  ///< the wall's or slot's width, the cylinder's diameter (scan units)
  int first = -1;          ///< index of its (first) surface
  int second = -1;         ///< the opposite plane; -1 for a cylinder
};

/// Options of findThinFeatures.
struct ThinFeatureOptions {
  double maxThickness = 0.0;  ///< report features thinner than this (scan units, > 0)
  double parallelAngle = 10.0;  ///< degrees: planes this near antiparallel count as opposite
  /// The planes face each other when at least this fraction of the sampled
  /// points of the one with fewer inliers, projected onto the other, have a
  /// point of it within `reach`.
  double overlap = 0.1;
  double reach = 0.0;           ///< scan units (> 0), e.g. a voxel
  std::size_t samples = 200;    ///< points sampled from each plane
  std::size_t minInliers = 30;  ///< surfaces with fewer inliers are ignored
};

/// The thin features of the scan's surfaces, thinnest first.
/// @throw std::invalid_argument when maxThickness or reach is not > 0.
std::vector<ThinFeature> findThinFeatures(const PointCloud& scan, std::span<const Surface> surfaces,
                                          const ThinFeatureOptions& options);

}  // namespace csgvox
