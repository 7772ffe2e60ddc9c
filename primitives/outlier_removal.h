#pragma once
/// Outliers of a raw scan: scattered points, and points off the surface
/// (mixed pixels at depth edges), found relative to the local spacing.

#include <cstddef>
#include <span>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// Options of findOutliers.
struct OutlierOptions {
  int neighbors = 12;  ///< k nearest neighbours of every test (count, >= 4)
  /// A point is scattered when its mean distance to its neighbours exceeds
  /// the median of its neighbours' own by more than this factor (ratio), and
  /// by more than robustSpread robust deviations of that ratio over the scan.
  double spacingRatio = 3.0;
  double robustSpread = 6.0;  ///< median absolute deviations, scaled to sigma (count)
  /// A point is also scattered when its mean distance to its neighbours
  /// exceeds this multiple of the scan's median (ratio): outliers far from
  /// the surface have other outliers as neighbours. A region sampled ten
  /// times more sparsely has about three times the spacing.
  double globalRatio = 5.0;
  /// A point is off the surface when its distance to the plane of its
  /// neighbours exceeds this many times their own RMS distance to it, this
  /// many times the scan's typical RMS distance (noise), and offSpacing
  /// times the neighbours' spacing, and its own spacing exceeds theirs by
  /// offRatio (a corner lies about one spacing off the plane of its
  /// neighbours, but as close to them as they are to each other).
  double offPlaneFactor = 5.0;
  double offSpacing = 1.0;  ///< multiple of the local spacing (see offPlaneFactor)
  double offRatio = 1.5;    ///< ratio of spacings (see offPlaneFactor)
};

/// Which points are outliers, and why.
struct Outliers {
  std::vector<bool> outlier;  ///< per point
  std::size_t scattered = 0;   ///< far from their neighbours, relative to their neighbours' spacing
  std::size_t offSurface = 0;  ///< off the plane of their neighbours, relative to its noise
  double spacing = 0.0;  ///< median mean distance of a point to its neighbours (scan units)
  double noise = 0.0;    ///< median RMS distance of neighbourhoods to their planes (scan units)
  std::size_t count() const { return scattered + offSurface; }
};

/// Finds the outliers of a scan. Everything is relative to the local
/// spacing and noise, so a region sampled ten times more sparsely than the
/// rest is not an outlier, nor is a thin feature whose neighbourhood spans
/// no plane (its neighbours' own distances to their plane are large).
/// Deterministic with any number of threads. Clouds of no more than
/// `neighbors` points have no outliers.
/// @throw std::invalid_argument if options.neighbors < 4.
Outliers findOutliers(std::span<const Vec3> points, const OutlierOptions& options = {});


}  // namespace csgvox
