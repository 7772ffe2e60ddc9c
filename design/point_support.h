#pragma once
/// Which scan points lie on which leaf of a fitted tree: the evidence behind
/// each designed value (its uncertainty shrinks with the points that hold
/// it) and behind the part's frame (directions vote with their points).

#include <span>
#include <vector>

#include "core/csg_tree.h"

namespace csgvox {

/// Options of pointSupport().
struct SupportOptions {
  double band = 3.0;         ///< a point lies on a surface within this many noise deviations
  double noiseFloor = 1e-6;  ///< least noise deviation, fraction of the points' diagonal
  double leastBand = 0.0;    ///< the band is at least this wide (scan units)
};

/// The points of a scan on the leaves of a tree.
struct PointSupport {
  double noise = 0.0;  ///< robust deviation of the tree's field at the points, scan units
  std::vector<const Node*> leaf;  ///< per point: the leaf whose surface it lies on, or nullptr
  std::vector<Vec3> gradient;     ///< per point: that leaf's field gradient there (inward normal)
  /// True when there are no points (the tree alone is known).
  bool empty() const { return leaf.empty(); }
};

/// Assigns each point to the leaf whose surface is nearest, when both that
/// surface and the tree's are within `band` noise deviations of it. The
/// noise is 1.4826 × the median of |f| of the tree at the points, floored.
/// Empty result for no points. @throw std::invalid_argument for an empty tree.
PointSupport pointSupport(const CsgTree& tree, std::span<const Vec3> points,
                          const SupportOptions& options = {});

}  // namespace csgvox
