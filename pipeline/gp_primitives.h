#pragma once
/// The primitives of the genetic-programming baseline (Fayolle & Pasko 2016,
/// §5.1–5.2): every fitted surface as an unbounded solid (a plane's
/// half-space, the inside of an infinite cylinder or cone, a sphere, a
/// torus) clipped to the scan's box, plus the separating half-spaces — the
/// faces of the minimal oriented box of each curved surface's inliers, and a
/// cylinder of the major radius for each torus — that are not already there.

#include <cstddef>
#include <span>

#include "core/point_cloud.h"
#include "core/surface.h"
#include "evolve/primitive_library.h"

namespace csgvox {

/// Options of gpPrimitives().
struct GpPrimitiveOptions {
  bool separators = true;    ///< add the separating primitives
  double samePlane = 0.01;   ///< planes closer than this (fraction of D) and parallel
                             ///< within sameAngle are one plane
  double sameAngle = 2.0;    ///< degrees
  double clipMargin = 0.05;  ///< the clip box is the scan's box grown by this, fraction of D
};

/// The library and where its primitives came from.
struct GpPrimitives {
  PrimitiveLibrary library;    ///< fitted solids first (in surface order), then separators
  std::size_t fitted = 0;      ///< primitives from the fitted surfaces
  std::size_t separators = 0;  ///< separating primitives added
  Aabb clipBox;                ///< the box unbounded solids are clipped to
};

/// Leaves are named like the baseline's: TYPE + index ("plane0",
/// "cylinder7"; separators "separator12").
/// @throw std::invalid_argument when the scan is empty or there are no surfaces.
GpPrimitives gpPrimitives(const PointCloud& scan, std::span<const Surface> surfaces,
                          const GpPrimitiveOptions& options = {});

}  // namespace csgvox
