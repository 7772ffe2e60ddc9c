#include "voxel/seen_bores.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace csgvox {

namespace {

constexpr int kSectors = 12;
// cos(15 degrees): a plane this close to across a bore's axis may be its floor.
constexpr double kFloorCosine = 0.9659258262890683;

// A concave cylinder seen all around its axis, and what lies inside it.
struct Bore {
  Vec3 point;                  // on the axis
  Vec3 axis;                   // unit
  double radius;               // scan units
  double lo, hi;               // span of the inliers along the axis, from `point`
  double density;              // inliers per unit area of the wall seen
  double interior;             // radius within which points are material across the bore
  std::vector<double> depths;  // sorted axial positions of the points within `interior`
  std::vector<std::pair<double, unsigned>> wall;  // the inliers' depths and sector bits, sorted
  bool crossed = false;  // material seen across it somewhere along its seen stretch
};

// The bore of a surface, or false when it is none: a concave cylinder at
// least minRadiusVoxels in radius with inliers in minSectors of the 12 sectors
// around its axis.
bool boreOf(const Surface& s, const PointCloud& scan, double voxel, const BoreOpeningOptions& o,
            Bore& out) {
  const auto* c = s.as<CylinderSurface>();
  if (c == nullptr || s.convex || s.inliers.empty() || c->radius < o.minRadiusVoxels * voxel) {
    return false;
  }
  const Vec3 axis = c->axisDir.normalized();
  const Mat3 frame = frameFromAxis(axis);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  unsigned sectors = 0;
  out.wall.clear();
  for (std::uint32_t i : s.inliers) {
    const Vec3 d = scan.points[i] - c->axisPoint;
    const double t = d.dot(axis);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    const double angle = std::atan2(d.dot(frame.col(1)), d.dot(frame.col(0)));
    const int k = std::clamp(int((angle + std::numbers::pi) / (2.0 * std::numbers::pi) * kSectors),
                             0, kSectors - 1);
    sectors |= 1u << k;
    out.wall.emplace_back(t, 1u << k);
  }
  std::sort(out.wall.begin(), out.wall.end());
  if (std::popcount(sectors) < o.minSectors || !(hi > lo)) return false;
  out.point = c->axisPoint;
  out.axis = axis;
  out.radius = c->radius;
  out.lo = lo;
  out.hi = hi;
  out.density = double(s.inliers.size()) / (2.0 * std::numbers::pi * c->radius * (hi - lo));
  out.interior = c->radius - voxel;
  out.depths.clear();
  for (const Vec3& p : scan.points) {
    const Vec3 d = p - out.point;
    const double t = d.dot(axis);
    if ((d - t * axis).squaredNorm() < out.interior * out.interior) out.depths.push_back(t);
  }
  std::sort(out.depths.begin(), out.depths.end());
  return true;
}

class BoreOpener {
 public:
  BoreOpener(const VoxelGrid& grid, VoxelSet& inside, const BoreOpeningOptions& o)
      : grid_(grid), inside_(inside), opened_(grid.voxelCount()), o_(o), h_(grid.voxelSize()) {}

  // Material across the bore in the slab one voxel thick about depth t:
  // points inside its disc (a floor, a boss standing in a round pocket) as
  // many as a share of the bore wall's own points in such a slab.
  bool closed(const Bore& b, double t) const {
    const auto first = std::lower_bound(b.depths.begin(), b.depths.end(), t - 0.5 * h_);
    const auto last = std::lower_bound(first, b.depths.end(), t + 0.5 * h_);
    const double wall = b.density * 2.0 * std::numbers::pi * b.radius * h_;
    return double(last - first) >= std::max(double(o_.minMaterialPoints), o_.materialShare * wall);
  }

  // The wall seen all around in the slab one voxel thick about depth t:
  // there the winding number of the points is reliable and the labels are
  // left alone.
  bool wallSeen(const Bore& b, double t) const {
    const auto first = std::lower_bound(b.wall.begin(), b.wall.end(),
                                        std::pair<double, unsigned>(t - 0.5 * h_, 0u));
    unsigned sectors = 0;
    for (auto it = first; it != b.wall.end() && it->first < t + 0.5 * h_; ++it) {
      sectors |= it->second;
    }
    return std::popcount(sectors) >= o_.minSectors;
  }

  // Opens the stretch of the bore between depths t0 < t1: inside voxels
  // whose centres lie in it become outside. (Leaving the winding number to
  // decide within a fraction of a voxel of the wall keeps the unseen wall's
  // ring of false inside voxels, and the optimisation adds members for it:
  // the pipe tee's scanner scan, 7 primitives for 4 with a quarter voxel.)
  std::size_t open(const Bore& b, double t0, double t1) {
    const double open2 = b.radius * b.radius;
    Aabb box;
    box.extend(b.point + t0 * b.axis);
    box.extend(b.point + t1 * b.axis);
    box.min.array() -= b.radius;
    box.max.array() += b.radius;
    std::array<int, 3> lo, hi;
    grid_.voxelRange(box, lo, hi);
    std::size_t n = 0;
    for (int k = lo[2]; k < hi[2]; ++k) {
      for (int j = lo[1]; j < hi[1]; ++j) {
        for (int i = lo[0]; i < hi[0]; ++i) {
          const std::size_t v = grid_.index(i, j, k);
          if (!inside_.test(v)) continue;
          const Vec3 d = grid_.center(i, j, k) - b.point;
          const double t = d.dot(b.axis);
          if (t < t0 || t > t1 || (d - t * b.axis).squaredNorm() >= open2) continue;
          inside_.reset(v);
          opened_.set(v);
          ++n;
        }
      }
    }
    return n;
  }

  // Along the stretch the inliers span, every run of slabs whose wall was
  // not seen all around and that no points close.
  std::size_t openSeen(Bore& b) {
    std::size_t n = 0;
    const double step = 0.5 * h_;
    double runStart = 0.0;
    bool inRun = false;
    for (double t = b.lo;; t += step) {
      const bool last = t >= b.hi;
      const double at = std::min(t, b.hi);
      const bool across = closed(b, at);
      b.crossed = b.crossed || across;
      const bool isOpen = !wallSeen(b, at) && !across;
      if (isOpen && !inRun) runStart = at, inRun = true;
      if (inRun && (!isOpen || last)) {
        const double end = isOpen ? at : at - step;
        if (end >= runStart) {
          n += open(b, std::max(b.lo, runStart - 0.5 * step), std::min(b.hi, end + 0.5 * step));
        }
        inRun = false;
      }
      if (last) break;
    }
    return n;
  }

  // The depth of the first plane past the end at depth `end` in direction
  // dir that could be the bore's floor: across the axis (within 15 degrees),
  // its outward normal facing back into the bore. Infinite (dir's sign) when
  // there is none. A hole that ends short of where a view would see its
  // floor most often ends at a face the part shows elsewhere (a hub's hole
  // at the top of the block it stands on).
  static double floorPast(const Bore& b, double end, int dir,
                          std::span<const PlaneSurface> planes) {
    double best = dir * std::numeric_limits<double>::infinity();
    for (const PlaneSurface& p : planes) {
      const double c = p.normal.dot(b.axis);
      if (std::abs(c) < kFloorCosine || dir * c > 0.0) continue;
      const double t = (p.offset - p.normal.dot(b.point)) / c;
      if (dir * (t - end) > 0.0 && dir * (t - best) < 0.0) best = t;
    }
    return best;
  }

  // Past the end at depth `end` in direction dir (+1 or -1): through a plug
  // of inside voxels that no floor closes, into air (a slab of the bore's
  // disc at least airShare outside: another bore's opened air, or the
  // outside of the part). The outside counts because a face no view saw
  // (the one a part stood on) is closed for the labels only where it is
  // material, seen from behind (primitives/unseen_faces.h): under a bore
  // whose floor no view saw, it is left open. It does not count for a bore
  // with material across it along its seen stretch (a boss standing in a
  // round pocket stands on its floor). Returns the voxels opened (0 when the
  // extension meets a floor, leaves the grid, or meets no plug within a
  // voxel of the end: the bore opens there already); a plane across the
  // axis, facing back into the bore, ends it first (floorPast).
  std::size_t extend(const Bore& b, double end, int dir, std::span<const PlaneSurface> planes,
                     bool& reached) {
    reached = false;
    const Mat3 frame = frameFromAxis(b.axis);
    const double floorAt = floorPast(b, end, dir, planes);
    bool plug = false;
    for (double t = end + 0.5 * dir * h_;; t += 0.5 * dir * h_) {
      if (closed(b, t)) return 0;
      if (dir * (t - floorAt) >= 0.0) {
        return open(b, std::min(end, floorAt), std::max(end, floorAt));
      }
      std::size_t total = 0, air = 0;
      const Vec3 centre = b.point + t * b.axis;
      for (double u = -b.interior; u <= b.interior; u += 0.5 * h_) {
        for (double w = -b.interior; w <= b.interior; w += 0.5 * h_) {
          if (u * u + w * w > b.interior * b.interior) continue;
          const std::size_t v = grid_.voxelOf(centre + u * frame.col(0) + w * frame.col(1));
          if (v == VoxelGrid::npos) continue;
          ++total;
          air += opened_.test(v) || (!b.crossed && !inside_.test(v)) ? 1 : 0;
        }
      }
      if (total == 0) return 0;  // out of the grid: no air met
      if (double(air) < o_.airShare * double(total)) {
        plug = true;
      } else if (plug) {
        reached = true;
        return open(b, std::min(end, t), std::max(end, t));
      } else if (std::abs(t - end) > h_) {
        return 0;
      }
    }
  }

 private:
  const VoxelGrid& grid_;
  VoxelSet& inside_;
  VoxelSet opened_;  // voxels openSeen turned to outside
  const BoreOpeningOptions& o_;
  double h_;
};

}  // namespace

BoreOpening openSeenBores(const VoxelGrid& grid, const PointCloud& scan,
                          std::span<const Surface> surfaces, VoxelSet& inside,
                          const BoreOpeningOptions& options) {
  BoreOpening out;
  if (!options.enabled || grid.voxelCount() == 0) return out;
  std::vector<Bore> bores;
  for (const Surface& s : surfaces) {
    Bore b;
    if (boreOf(s, scan, grid.voxelSize(), options, b)) bores.push_back(std::move(b));
  }
  out.bores = bores.size();
  std::vector<PlaneSurface> planes;
  for (const Surface& s : surfaces) {
    if (const auto* p = s.as<PlaneSurface>()) planes.push_back(*p);
  }
  BoreOpener opener(grid, inside, options);
  // Every seen stretch first, so an extension can reach another bore's air.
  for (Bore& b : bores) out.voxels += opener.openSeen(b);
  for (const Bore& b : bores) {
    for (int dir : {-1, 1}) {
      bool reached = false;
      out.voxels += opener.extend(b, dir < 0 ? b.lo : b.hi, dir, planes, reached);
      out.extended += reached ? 1 : 0;
    }
  }
  return out;
}

}  // namespace csgvox
