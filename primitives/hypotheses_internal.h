#pragma once
/// Internal to the hypothesis generator (hypotheses.cpp, cuboid_hypotheses.cpp,
/// quadric_hypotheses.cpp): shared helpers. Not part of the public API.

#include <array>
#include <span>
#include <unordered_map>
#include <vector>

#include "primitives/hypotheses.h"
#include "primitives/min_area_rectangle.h"

namespace csgvox::hypotheses_detail {

/// Everything the generators share: the input, the options and the derived
/// scale-dependent thresholds.
struct Context {
  const PointCloud& scan;
  std::span<const Surface> surfaces;
  const HypothesisOptions& options;
  double voxel = 0.0;          ///< fit threshold, scan units
  double diagonal = 0.0;       ///< D (oriented bounding-box diagonal), scan units
  double lengthTol = 0.0;      ///< duplicate tolerance, scan units
  double cosParallel = 1.0;    ///< cos(parallelTolerance)
  double sinOrthogonal = 0.0;  ///< sin(orthogonalTolerance)
};

/// Surfaces with fewer inliers are skipped.
inline constexpr std::size_t kMinInliers = 4;

/// A closed interval.
struct Range {
  double lo = 0.0;
  double hi = 0.0;
  double size() const { return hi - lo; }
};

/// The extent of `values` (positions along an axis of points with Gaussian
/// noise of standard deviation `sigma` across it): the extremes, pulled in by
/// half as many values as the noise is expected to push past a straight edge
/// of a uniformly sampled region (n·sigma / (range·sqrt(2 pi))). With
/// sigma = 0, the exact min and max. `values` must not be empty.
Range robustRange(std::vector<double> values, double sigma);

/// `range` (robustRange of `values`) without its sparse ends: the positions
/// along a cylinder's axis of its inliers are uniformly dense over the
/// patch, and an end where fewer than a quarter of the typical density lie
/// is not the patch but the noise tail of a neighbouring surface that the
/// cylinder's band reached (the head of a bolt around a thin noisy shank).
/// The density is counted in bins of about 50 values; the typical one is
/// the median of the non-empty bins, and each end moves in to the first run
/// of three bins at least that dense. Returns `range` for fewer than 800
/// values.
Range denseRange(std::span<const double> values, Range range);

/// The box with unit axes `frame` (columns, right-handed) spanning `ranges`
/// (coordinates along the frame's axes).
Box boxFromRanges(const Mat3& frame, const std::array<Range, 3>& ranges);

/// The minimal box's orientation is searched on at most this many points.
inline constexpr std::size_t kBoxSearchPoints = 300;

/// Axes (columns, right-handed) of the minimal oriented bounding box of the
/// points: minimalBoxFrame with `seed`, searched on kBoxSearchPoints evenly
/// spread points.
Mat3 searchedBoxFrame(std::span<const Vec3> points, std::uint32_t seed);

/// A plane surface of the input, by index.
struct PlaneRef {
  std::size_t index = 0;                ///< index in Context::surfaces
  const Surface* surface = nullptr;     ///< the surface
  const PlaneSurface* plane = nullptr;  ///< its plane
};
/// The plane surfaces with at least kMinInliers inliers, in input order.
std::vector<PlaneRef> planeSurfaces(const Context& ctx);

/// The inlier positions of a surface.
std::vector<Vec3> inlierPoints(const PointCloud& scan, const Surface& surface);

/// Same primitive geometrically: same type, axes parallel within cosTol
/// (|cos| >= cosTol; box axes in any order and sign), lengths within
/// lengthTol. A half-space and its complement count as the same (one plane).
bool samePrimitive(const Primitive& a, const Primitive& b, double lengthTol, double cosTol);

/// Finds, among inserted points of a fixed dimension, those that may lie
/// within `tolerance` of a query in every coordinate (a superset: callers
/// check exactly). Cells are 2·tolerance wide, so a query visits at most two
/// cells per coordinate.
class ToleranceGrid {
 public:
  ToleranceGrid(std::size_t dimensions, double tolerance);
  /// Adds a point with an id.
  void insert(std::span<const double> x, std::size_t id);
  /// Calls visit(id) for the ids in the cells within tolerance of x, until it returns true;
  /// returns whether it did.
  template <class Visit>
  bool any(std::span<const double> x, Visit&& visit) const {
    std::vector<long long> lo(dims_), hi(dims_), key(dims_);
    for (std::size_t k = 0; k < dims_; ++k) {
      lo[k] = cell(x[k] - tol_);
      hi[k] = cell(x[k] + tol_);
      key[k] = lo[k];
    }
    while (true) {
      if (const auto it = cells_.find(hash(key)); it != cells_.end()) {
        for (const Entry& e : it->second) {
          if (e.key == key && visit(e.id)) return true;
        }
      }
      std::size_t k = 0;
      while (k < dims_ && key[k] == hi[k]) key[k] = lo[k], ++k;
      if (k == dims_) return false;
      ++key[k];
    }
  }

 private:
  struct Entry {
    std::vector<long long> key;
    std::size_t id;
  };
  long long cell(double v) const;
  static std::size_t hash(const std::vector<long long>& key);
  std::size_t dims_;
  double tol_;
  std::unordered_map<std::size_t, std::vector<Entry>> cells_;
};

/// Cuboid hypotheses (Wu §3.1). Marks in `planeInCuboid` (indexed by surface)
/// the planes that are faces of a kept cuboid built from two or more patches.
std::vector<Candidate> cuboidCandidates(const Context& ctx, CuboidStats& stats,
                                        std::vector<char>& planeInCuboid);

/// Quadric primitives, additional boxes, indirect candidates and separators
/// (Wu §3.2, §4.1; Fayolle §5.2).
std::vector<Candidate> quadricCandidates(const Context& ctx, HypothesisStats& stats);

}  // namespace csgvox::hypotheses_detail
