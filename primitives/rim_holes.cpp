#include "primitives/rim_holes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <tuple>
#include <vector>

#include "core/nearest_neighbors.h"
#include "core/statistics.h"
#include "primitives/min_area_rectangle.h"
#include "primitives/surface_fit_internal.h"

namespace csgvox {

namespace {

using Vec2 = Eigen::Vector2d;

// Angular sectors around a gap's centre; each must hold a rim point.
constexpr int kSectors = 12;
// Points of one face searched for gaps, at most.
constexpr std::size_t kMaxFacePoints = 40000;
// Cells of one face's distance map, at most (the cell grows to fit).
constexpr double kMaxCells = 1e6;
// Two faces are parallel (or opposite) when their normals' dot product is
// beyond this (about 11 degrees).
constexpr double kParallel = 0.98;
// Planes are one face when their normals' dot product is beyond this (about
// 5.7 degrees) and their offsets within two epsilon.
constexpr double kCoplanar = 0.995;
// A wall point's normal makes at least 45 degrees with the hole's axis
// (|cos| at most this).
constexpr double kAcrossAxis = 0.7;
// A free point faces a plane's way when its normal is within about 45
// degrees of the plane's (cosine at least this).
constexpr double kFacing = 0.7;
// The empty circles that tell a rim's sampling lie within this many radii
// of its centre (ratio), and are at least this many (count).
constexpr double kPeakWindow = 6.0;
constexpr std::size_t kMinPeaks = 6;
// A surface that meets a face at less than 30 degrees runs along it rather
// than through it: the mean distance to it from two points a step either
// side of the face, over the step, is then above this (cos 30 degrees; a
// hole's wall gives about 0, a 90-degree countersink's cone 0.71).
constexpr double kTangent = 0.87;
// Stretches along a window's side, at most, each at least two point spacings
// long, each of which must hold a point near the side (a window's sectors).
constexpr int kSideStretches = 6;
// Fewest points that show a hole's bottom face or its wall.
constexpr std::size_t kMinEvidence = 4;

// A round gap in one plane's points.
struct Rim {
  std::size_t plane = 0;
  Vec3 normal = Vec3::UnitZ();  // the plane's outward normal
  Vec3 center = Vec3::Zero();   // on the plane
  double radius = 0.0;
  double spacing = 0.0;               // of the face's points it was found among
  std::vector<std::uint32_t> points;  // the plane's inliers around the gap
  // A rectangular gap (a window) instead of a round one: `center` is the
  // rectangle's, `along` the unit direction of its longer side (in the
  // plane), `halfLength` >= `halfWidth` its half sides (`radius` unused).
  bool window = false;
  Vec3 along = Vec3::UnitX();
  double halfLength = 0.0;
  double halfWidth = 0.0;
};

// A face's points in its plane (2D), on a grid of cells about one point
// spacing wide: the points of each cell, and the distance from each cell's
// centre to the nearest point (the room among the points).
struct FaceGrid {
  Vec2 lo = Vec2::Zero();
  double cell = 0.0;
  int w = 0, h = 0;
  std::vector<std::uint32_t> start, members;  // each cell's points (compressed rows)
  std::vector<double> empty;                  // per cell

  Vec2 centre(int x, int y) const {
    return Vec2(lo.x() + (x + 0.5) * cell, lo.y() + (y + 0.5) * cell);
  }
  std::size_t cellOf(const Vec2& p) const {
    const int x = std::clamp(int(std::floor((p.x() - lo.x()) / cell)), 0, w - 1);
    const int y = std::clamp(int(std::floor((p.y() - lo.y()) / cell)), 0, h - 1);
    return std::size_t(y) * std::size_t(w) + std::size_t(x);
  }
  // Calls f(k) for each point k of the cells that the box [a, b] reaches.
  template <class F>
  void forEachNear(const Vec2& a, const Vec2& b, F&& f) const {
    const std::size_t c0 = cellOf(a), c1 = cellOf(b);
    for (std::size_t y = c0 / std::size_t(w); y <= c1 / std::size_t(w); ++y) {
      for (std::size_t x = c0 % std::size_t(w); x <= c1 % std::size_t(w); ++x) {
        const std::size_t c = y * std::size_t(w) + x;
        for (std::uint32_t m = start[c]; m < start[c + 1]; ++m) f(members[m]);
      }
    }
  }
};

// A local maximum of a face's distance map: the centre and radius of an
// empty circle among its points.
struct Peak {
  Vec2 center;
  double radius;
};

// A rectangle in a face's plane (2D): a window's outline.
struct WindowShape {
  Vec2 center = Vec2::Zero();
  Vec2 along = Vec2::UnitX();  // unit, along the longer side
  double halfLength = 0.0;
  double halfWidth = 0.0;

  // (along, across) coordinates of q about the centre.
  Vec2 local(const Vec2& q) const {
    const Vec2 d = q - center;
    return Vec2(d.dot(along), d.x() * along.y() - d.y() * along.x());
  }
  // How far q lies outside the rectangle, in the larger of the two
  // directions (negative inside).
  double outside(const Vec2& q) const {
    const Vec2 l = local(q);
    return std::max(std::abs(l.x()) - halfLength, std::abs(l.y()) - halfWidth);
  }
};

// The rectangle of the gap around `seed` (a maximum of the distance map
// whose gap is not round), when the face's points follow four straight
// sides around it: the empty room farther than half the seed's radius from
// every point (the gap shrunk by that much, its corners kept) gives the
// rectangle's orientation (its minimum-area rectangle) and the sides' first
// places; along each side the nearest point (of the face's, or of `edges`)
// of each stretch two spacings long must be there, at one distance (their spread at most
// `roundness` times the half width plus `roundnessSpacings` spacings, as a round rim's sectors),
// and the side lies at their median. The room must not reach the grid's border (a notch in the
// face's edge), and the rectangle may hold no more than kMinEvidence points two spacings in from
// its sides (the strips along a thin wall's window sides hold points of blended normals).
bool findWindow(const std::vector<Vec3>& flat, const std::vector<Vec2>& edges, const FaceGrid& grid,
                const Peak& seed, double spacing, double maxHalf, const RimHoleOptions& options,
                WindowShape& out) {
  const double theta = 0.5 * seed.radius;
  const std::size_t maxCells =
      std::size_t(std::ceil(4.0 * maxHalf * maxHalf / (grid.cell * grid.cell))) + 1;
  std::vector<char> seen(grid.empty.size(), 0);
  std::vector<std::size_t> queue{grid.cellOf(seed.center)};
  seen[queue.front()] = 1;
  std::vector<Vec2> room;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const std::size_t c = queue[q];
    const int x = int(c % std::size_t(grid.w)), y = int(c / std::size_t(grid.w));
    if (x == 0 || y == 0 || x + 1 == grid.w || y + 1 == grid.h) return false;
    if (queue.size() > maxCells) return false;
    room.push_back(grid.centre(x, y));
    for (const std::size_t n : {c - 1, c + 1, c - std::size_t(grid.w), c + std::size_t(grid.w)}) {
      if (!seen[n] && grid.empty[n] >= theta) {
        seen[n] = 1;
        queue.push_back(n);
      }
    }
  }
  if (room.size() < 3) return false;
  WindowShape shape;
  shape.center = seed.center;
  shape.along = minAreaRectangle(room).direction.normalized();
  if (!shape.along.allFinite()) return false;
  // The room's extent along and across, about the seed.
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  Vec2 boxLo = lo, boxHi = hi;
  for (const Vec2& c : room) {
    const Vec2 l = shape.local(c);
    lo = lo.cwiseMin(l);
    hi = hi.cwiseMax(l);
    boxLo = boxLo.cwiseMin(c);
    boxHi = boxHi.cwiseMax(c);
  }
  const double reach = theta + 3.0 * spacing + grid.cell;
  std::vector<Vec2> near;  // the points around the room, in (along, across)
  grid.forEachNear(boxLo - Vec2::Constant(reach), boxHi + Vec2::Constant(reach),
                   [&](std::uint32_t k) { near.push_back(shape.local(flat[k].head<2>())); });
  for (const Vec2& q : edges) {
    if ((q.array() >= boxLo.array() - reach).all() && (q.array() <= boxHi.array() + reach).all()) {
      near.push_back(shape.local(q));
    }
  }
  // Each side: its axis (0 along, 1 across) and its sign.
  const double halfWidth0 = 0.5 * (hi.y() - lo.y()) + theta;
  std::array<double, 4> place{};  // of each side, signed along its axis
  for (int side = 0; side < 4; ++side) {
    const int e = side / 2, t = 1 - e;
    const double sign = side % 2 == 0 ? 1.0 : -1.0;
    const double edge = sign > 0.0 ? hi[e] : -lo[e];
    const double t0 = lo[t], t1 = hi[t];
    const int stretches = std::clamp(int((t1 - t0) / (2.0 * spacing)), 1, kSideStretches);
    std::vector<double> nearest(std::size_t(stretches), std::numeric_limits<double>::infinity());
    for (const Vec2& l : near) {
      const double d = sign * l[e];
      if (d <= edge || d > edge + reach || l[t] < t0 || l[t] > t1) continue;
      const int k = std::min(stretches - 1, int((l[t] - t0) / (t1 - t0 + 1e-300) * stretches));
      nearest[std::size_t(k)] = std::min(nearest[std::size_t(k)], d);
    }
    std::vector<double> found;
    for (double d : nearest) {
      if (std::isfinite(d)) found.push_back(d);
    }
    if (found.empty() || found.size() + 1 < nearest.size()) return false;
    std::sort(found.begin(), found.end());
    const std::size_t n = found.size();
    const double spread = n >= 4 ? found[n - 2] - found[1] : found.back() - found.front();
    if (spread > options.roundness * halfWidth0 + options.roundnessSpacings * spacing) {
      return false;
    }
    place[std::size_t(side)] = median(std::move(found));
  }
  // The rectangle between the sides; the longer side first.
  Vec2 mid(0.5 * (place[0] - place[1]), 0.5 * (place[2] - place[3]));
  Vec2 half(0.5 * (place[0] + place[1]), 0.5 * (place[2] + place[3]));
  shape.center += mid.x() * shape.along + mid.y() * Vec2(shape.along.y(), -shape.along.x());
  if (half.x() < half.y()) {
    shape.along = Vec2(shape.along.y(), -shape.along.x());
    std::swap(half.x(), half.y());
  }
  shape.halfLength = half.x();
  shape.halfWidth = half.y();
  if (!(shape.halfWidth >= options.minRadiusSpacings * spacing) || shape.halfLength > maxHalf) {
    return false;
  }
  // Nothing inside it (a spacing in from its sides).
  std::size_t inside = 0;
  grid.forEachNear(boxLo - Vec2::Constant(reach), boxHi + Vec2::Constant(reach),
                   [&](std::uint32_t k) {
                     inside += shape.outside(flat[k].head<2>()) < -2.0 * spacing ? 1 : 0;
                   });
  if (inside > kMinEvidence) return false;
  out = shape;
  return true;
}

// The round gaps among the inliers of the coplanar plane surfaces `group`
// (detection may split one face among several; the first holds the most
// points and stands for them) and the points of `unassigned` that
// lie on the face: the largest empty circles among its points
// (maxima of their distance map on a grid of one point spacing) whose edge
// the points follow all around. An empty circle
// does not need the face closed around it: a hole near the edge of a narrow
// face, whose rim the scan breaks, still counts.
void findRims(const PointCloud& cloud, const DetectionResult& result,
              const std::vector<std::size_t>& group, const std::vector<std::uint32_t>& unassigned,
              const RimHoleOptions& options, std::vector<Rim>& rims, RimHoleStats& stats) {
  const std::size_t s = group.front();
  const auto* plane = result.surfaces[s].as<PlaneSurface>();
  std::vector<std::uint32_t> inliers;
  for (std::size_t t : group) {
    const std::vector<std::uint32_t>& more = result.surfaces[t].inliers;
    inliers.insert(inliers.end(), more.begin(), more.end());
  }
  if (inliers.size() < options.minPlaneInliers) return;
  // The face's points that no surface holds: within epsilon of the plane,
  // facing its way. Estimated normals blend at a face's edges, so the strip
  // along an edge, and the narrow land between a hole and an edge, often
  // falls out of the plane's inliers; without it the rim of a hole near an
  // edge is broken on that side, and the gap is not round.
  for (std::uint32_t i : unassigned) {
    if (std::abs(cloud.points[i].dot(plane->normal) - plane->offset) > result.epsilon) continue;
    if (cloud.normals[i].dot(plane->normal) < kFacing) continue;
    inliers.push_back(i);
  }
  // A face of a big scan is searched on every k-th of its points: the gaps
  // that matter are several spacings wide, and the distance map's cells
  // follow the spacing.
  if (inliers.size() > kMaxFacePoints) {
    std::sort(inliers.begin(), inliers.end());
    const std::size_t n = inliers.size();
    std::vector<std::uint32_t> every;
    for (std::size_t k = 0; k < kMaxFacePoints; ++k) {
      every.push_back(inliers[k * n / kMaxFacePoints]);
    }
    inliers = std::move(every);
  }
  const Mat3 frame = frameFromAxis(plane->normal);
  const Vec3 u = frame.col(0), v = frame.col(1);
  // The points in the plane's frame (z = 0), for distances along it.
  std::vector<Vec3> flat(inliers.size());
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    const Vec3& p = cloud.points[inliers[k]];
    flat[k] = Vec3(p.dot(u), p.dot(v), 0.0);
    lo = lo.cwiseMin(flat[k].head<2>());
    hi = hi.cwiseMax(flat[k].head<2>());
  }
  const NearestNeighbors nn(flat);
  // (The thresholds below were measured with this estimate on at most 2000
  // points: estimateSpacing's, on 4000 with the mean of the two middle
  // values, moves borderline rims either way.)
  const double spacing = medianNearestDistance(flat, nn);
  if (!(spacing > 0.0)) return;
  FaceGrid grid;
  grid.lo = lo;
  grid.cell = spacing;
  const Vec2 size = hi - lo;
  if ((size.x() / grid.cell + 1.0) * (size.y() / grid.cell + 1.0) > kMaxCells) {
    grid.cell = std::sqrt(size.x() * size.y() / kMaxCells) + 1e-12 * (size.x() + size.y());
  }
  grid.w = int(size.x() / grid.cell) + 1;
  grid.h = int(size.y() / grid.cell) + 1;
  const int w = grid.w, h = grid.h;
  const std::size_t cells = std::size_t(w) * std::size_t(h);
  grid.start.assign(cells + 1, 0);
  grid.members.resize(flat.size());
  for (const Vec3& p : flat) ++grid.start[grid.cellOf(p.head<2>()) + 1];
  for (std::size_t c = 0; c < cells; ++c) grid.start[c + 1] += grid.start[c];
  {
    std::vector<std::uint32_t> fill(grid.start.begin(), grid.start.end() - 1);
    for (std::size_t k = 0; k < flat.size(); ++k) {
      grid.members[fill[grid.cellOf(flat[k].head<2>())]++] = std::uint32_t(k);
    }
  }
  grid.empty.resize(cells);
  {
    std::vector<std::uint32_t> near;
    std::vector<double> d2;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const Vec2 c = grid.centre(x, y);
        nn.kNearest(Vec3(c.x(), c.y(), 0.0), 1, near, &d2);
        grid.empty[std::size_t(y) * std::size_t(w) + std::size_t(x)] = std::sqrt(d2[0]);
      }
    }
  }
  const double minRadius = options.minRadiusSpacings * spacing;
  const double maxRadius = options.maxRadius * result.diagonal;
  // Centres: local maxima of the distance (the sector test below tells a
  // hole from the room beside a face's edge).
  std::vector<Peak> candidates;
  std::vector<Peak> peaks;  // every local maximum of the distance
  for (int y = 1; y + 1 < h; ++y) {
    for (int x = 1; x + 1 < w; ++x) {
      const std::size_t c = std::size_t(y) * std::size_t(w) + std::size_t(x);
      const double r = grid.empty[c];
      if (r > maxRadius) continue;
      bool peak = true;
      for (int dy = -1; dy <= 1 && peak; ++dy) {
        for (int dx = -1; dx <= 1 && peak; ++dx) {
          const std::size_t n = std::size_t(y + dy) * std::size_t(w) + std::size_t(x + dx);
          // Ties go to the first cell, so a plateau gives one peak.
          if (n != c && (grid.empty[n] > r || (grid.empty[n] == r && n < c))) peak = false;
        }
      }
      if (!peak) continue;
      peaks.push_back({grid.centre(x, y), r});
      if (r >= minRadius) candidates.push_back({grid.centre(x, y), r});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Peak& a, const Peak& b) {
    return std::tuple(-a.radius, a.center.x(), a.center.y()) <
           std::tuple(-b.radius, b.center.x(), b.center.y());
  });
  std::vector<Peak> taken;
  std::vector<WindowShape> windows;
  std::vector<std::uint32_t> near;
  std::vector<double> d2;
  // The median radius of the empty circles (the distance map's maxima)
  // around a gap, out to kPeakWindow of its radius; 0 below kMinPeaks of them.
  const auto typicalGap = [&](const auto& beyond, double radius) {
    std::vector<double> around;
    for (const Peak& p : peaks) {
      const double d = beyond(p.center);
      if (d > spacing && d < (kPeakWindow - 1.0) * radius) around.push_back(p.radius);
    }
    return around.size() >= kMinPeaks ? median(std::move(around)) : 0.0;
  };
  // The gap's rim: the points of `pool` (indices into flat) within two
  // spacings outside its outline (`beyond(q)`: how far q lies outside it).
  // The gap must be wide for their own spacing (a sparse patch has gaps of a
  // spacing or two) and for the sampling around it: a scanner's rows leave a
  // regular pattern of empty circles one or two spacings wide (rows further
  // apart than the points along a row, which the spacing measures); a hole
  // is much wider than the typical empty circle beside it.
  const auto wideRim = [&](const std::vector<std::size_t>& pool, const auto& beyond, double radius,
                           std::vector<std::uint32_t>& ring) {
    std::vector<double> gaps;
    for (std::size_t k : pool) {
      if (beyond(flat[k].head<2>()) > 2.0 * spacing) continue;
      ring.push_back(inliers[k]);
      nn.kNearest(flat[k], 2, near, &d2);
      if (d2.size() == 2) gaps.push_back(std::sqrt(d2[1]));
    }
    if (gaps.empty() || radius < options.minRadiusSpacings * median(std::move(gaps))) return false;
    return !(radius < options.minPeakRatio * typicalGap(beyond, radius));
  };
  // The points within epsilon of the face that do not face its way: the
  // strips along its edges where estimated normals blend, and the tops of
  // the walls that meet it. A window's sides lie where they are, often a
  // spacing or two in from the face's own points. Gathered for the face's
  // first gap that is not round (most faces have none).
  std::vector<Vec2> edges;
  bool edgesGathered = false;
  // A gap that is not round may be a rectangle (a window or a slot).
  const auto tryWindow = [&](const Peak& cand) {
    if (!options.windows) return;
    if (!edgesGathered) {
      edgesGathered = true;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Vec3& p = cloud.points[i];
        if (std::abs(p.dot(plane->normal) - plane->offset) > result.epsilon ||
            cloud.normals[i].dot(plane->normal) >= kFacing) {
          continue;
        }
        edges.emplace_back(p.dot(u), p.dot(v));
      }
    }
    WindowShape shape;
    if (!findWindow(flat, edges, grid, cand, spacing, maxRadius, options, shape)) return;
    const Vec2 reachOut = Vec2::Constant(shape.halfLength + 3.0 * spacing);
    std::vector<std::size_t> pool;
    grid.forEachNear(shape.center - reachOut, shape.center + reachOut,
                     [&](std::uint32_t k) { pool.push_back(k); });
    std::vector<std::uint32_t> ring;
    if (!wideRim(
            pool, [&](const Vec2& q) { return shape.outside(q); }, shape.halfWidth, ring)) {
      return;
    }
    windows.push_back(shape);
    ++stats.windowGaps;
    Rim r;
    r.plane = s;
    r.normal = plane->normal;
    r.center = plane->offset * plane->normal + shape.center.x() * u + shape.center.y() * v;
    r.spacing = spacing;
    r.points = std::move(ring);
    r.window = true;
    r.along = (shape.along.x() * u + shape.along.y() * v).normalized();
    r.halfLength = shape.halfLength;
    r.halfWidth = shape.halfWidth;
    rims.push_back(std::move(r));
  };
  for (const Peak& cand : candidates) {
    if (std::any_of(taken.begin(), taken.end(),
                    [&](const Peak& t) {
                      return (t.center - cand.center).norm() < t.radius + cand.radius;
                    }) ||
        std::any_of(windows.begin(), windows.end(),
                    [&](const WindowShape& t) { return t.outside(cand.center) < cand.radius; })) {
      continue;
    }
    // How ragged the rim may be: the sampling's typical empty circle around
    // it, where the scanner's rows leave it wider than the spacing.
    const double typical = typicalGap(
        [&](const Vec2& q) { return (q - cand.center).norm() - cand.radius; }, cand.radius);
    const double ragged =
        std::max(options.roundnessSpacings * spacing, options.roundnessGaps * typical);
    // The points around the circle (from the cells it reaches), out to two
    // of the rows' gaps for the sectors, then its centre fitted to those
    // within two spacings (farther out a circle fitted to a ring of rows
    // wanders).
    const double fitReach = cand.radius * (1.0 + options.roundness) + 2.0 * spacing;
    const double reach = cand.radius * (1.0 + options.roundness) + 2.0 * std::max(spacing, typical);
    std::vector<std::size_t> band;
    std::vector<std::uint32_t> bandPoints;  // scan indices, within fitReach
    grid.forEachNear(cand.center - Vec2::Constant(reach), cand.center + Vec2::Constant(reach),
                     [&](std::uint32_t k) {
                       const double d = (flat[k].head<2>() - cand.center).norm();
                       if (d > reach) return;
                       band.push_back(k);
                       if (d <= fitReach) bandPoints.push_back(inliers[k]);
                     });
    const Vec3 origin = plane->offset * plane->normal + cand.center.x() * u + cand.center.y() * v;
    Vec2 center = cand.center;
    Vec3 fitted;
    if (double r; surface_fit_detail::fitCircle(cloud, bandPoints, origin, u, v, fitted, r)) {
      const Vec2 f(fitted.dot(u), fitted.dot(v));
      if ((f - cand.center).norm() <= std::max(spacing, 0.25 * cand.radius)) center = f;
    }
    // The nearest point of each sector: a round hole's rim lies at its
    // radius all around, a slot's, a square's or a face's notch does not.
    std::array<double, kSectors> nearest;
    nearest.fill(std::numeric_limits<double>::infinity());
    for (std::size_t k : band) {
      const Vec2 d = flat[k].head<2>() - center;
      const double angle = std::atan2(d.y(), d.x()) + std::numbers::pi;
      const int sector = std::min(kSectors - 1, int(angle / (2.0 * std::numbers::pi) * kSectors));
      nearest[std::size_t(sector)] = std::min(nearest[std::size_t(sector)], d.norm());
    }
    if (!std::all_of(nearest.begin(), nearest.end(), [](double r) { return std::isfinite(r); })) {
      tryWindow(cand);
      continue;
    }
    std::array<double, kSectors> sorted = nearest;
    std::sort(sorted.begin(), sorted.end());
    const double radius = 0.5 * (sorted[kSectors / 2 - 1] + sorted[kSectors / 2]);
    // (The nearest and the farthest sector left out: on a sparse rim one
    // sector may hold its nearest point a spacing or more out.)
    if (radius > maxRadius ||
        sorted[kSectors - 2] - sorted[1] > options.roundness * radius + ragged) {
      tryWindow(cand);
      continue;
    }
    std::vector<std::uint32_t> ring;
    if (!wideRim(
            band, [&](const Vec2& q) { return (q - center).norm() - radius; }, radius, ring)) {
      continue;
    }
    taken.push_back({center, radius});
    ++stats.gaps;
    Rim r;
    r.plane = s;
    r.normal = plane->normal;
    r.center = plane->offset * plane->normal + center.x() * u + center.y() * v;
    r.radius = radius;
    r.spacing = spacing;
    r.points = std::move(ring);
    rims.push_back(std::move(r));
  }
}

// True when a curved surface passes along most of the rim's circle (within
// two epsilon plus the circle's own uncertainty, a point spacing): the hole's
// wall, a countersink or a boss standing on the face was found already.
bool explained(const DetectionResult& result, const Rim& rim) {
  constexpr int kSamples = 24;
  const Mat3 frame = frameFromAxis(rim.normal);
  const double tolerance = 2.0 * result.epsilon + rim.spacing;
  for (const Surface& surface : result.surfaces) {
    if (surface.as<PlaneSurface>()) continue;
    int near = 0;
    for (int k = 0; k < kSamples; ++k) {
      const double a = 2.0 * std::numbers::pi * k / kSamples;
      const Vec3 p =
          rim.center + rim.radius * (std::cos(a) * frame.col(0) + std::sin(a) * frame.col(1));
      if (surfaceDistance(surface, p) > tolerance) continue;
      // A wall crosses the face steeply; a surface nearly tangent to it
      // (a round fitted along the face's edge) passes near every point of
      // a strip of the face and explains nothing.
      const double step = 4.0 * tolerance;
      const double slope = (surfaceDistance(surface, p + step * rim.normal) +
                            surfaceDistance(surface, p - step * rim.normal)) /
                           (2.0 * step);
      if (slope > kTangent) continue;
      ++near;
    }
    if (2 * near >= kSamples) return true;
  }
  return false;
}

// True when the heights above a face of the points facing its way, inside
// a gap (`inside`) and around it (`around`), show a cap: at least
// kMinEvidence inside at one height (within `eps` of their median) and fewer
// than a quarter as many at that height around it. A rod or a bar standing
// through the face shows its top so; a face above the gap that reaches past
// it (an overhang's) does not.
bool isCap(const std::vector<double>& inside, const std::vector<double>& around, double eps) {
  if (inside.size() < kMinEvidence) return false;
  const double top = median(inside);
  const auto atTop = [&](const std::vector<double>& heights) {
    return std::size_t(std::count_if(heights.begin(), heights.end(),
                                     [&](double t) { return std::abs(t - top) <= eps; }));
  };
  const std::size_t cap = atTop(inside);
  return cap >= kMinEvidence && 4 * atTop(around) < cap;
}

// Component of d across the unit axis n.
Vec3 lateral(const Vec3& d, const Vec3& n) { return d - d.dot(n) * n; }

// The windows: a rectangular gap in a face with the same gap in the
// opposite face (a window or a slot through a wall) becomes the planes of
// its four sides, each holding the two rims' points along it and the side's
// own points that no surface holds (a scanner sees a thin wall's window
// sides at a grazing angle, if at all). A side where a plane was found
// already keeps it; a window whose four sides were all found is left alone.
// As for a hole, points inside the window between the faces veto it, and so
// does the top of a bar standing through the wall.
void addWindows(const PointCloud& cloud, const std::vector<Rim>& rims, std::vector<char>& used,
                DetectionResult& result, RimHoleStats& stats) {
  const double eps = result.epsilon;
  // The surfaces there were before (the round holes added are no planes).
  const std::size_t detected = result.surfaces.size();
  for (std::size_t a = 0; a < rims.size(); ++a) {
    if (used[a] || !rims[a].window) continue;
    const Rim& ra = rims[a];
    const Vec3 n = ra.normal;
    std::size_t partner = rims.size();
    double depth = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < rims.size(); ++b) {
      const Rim& rb = rims[b];
      if (used[b] || b == a || !rb.window || rb.normal.dot(n) > -kParallel) continue;
      const Vec3 d = rb.center - ra.center;
      const double along = -d.dot(n);
      if (along <= eps || std::abs(rb.along.dot(ra.along)) < kParallel) continue;
      if (lateral(d, n).norm() > std::max(0.25 * std::min(ra.halfWidth, rb.halfWidth), 2.0 * eps)) {
        continue;
      }
      if (std::max(ra.halfLength, rb.halfLength) > 1.4 * std::min(ra.halfLength, rb.halfLength) ||
          std::max(ra.halfWidth, rb.halfWidth) > 1.4 * std::min(ra.halfWidth, rb.halfWidth)) {
        continue;
      }
      if (along < depth) depth = along, partner = b;
    }
    if (partner == rims.size()) continue;
    const Rim& rb = rims[partner];
    // The window: the overlap of the two gaps (a sparse face shows a gap
    // larger than the window, never smaller), in the frame (e0, e1) about
    // the first rim's centre: [lo.x, hi.x] x [lo.y, hi.y].
    const Vec3 e0 = ra.along, e1 = n.cross(e0);
    Vec2 lo = Vec2::Constant(-std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Rim* rim : {&ra, &rb}) {
      const Vec3 c = lateral(rim->center - ra.center, n);
      const double l0 = rim->halfLength, l1 = rim->halfWidth;
      lo = lo.cwiseMax(Vec2(c.dot(e0) - l0, c.dot(e1) - l1));
      hi = hi.cwiseMin(Vec2(c.dot(e0) + l0, c.dot(e1) + l1));
    }
    const double band = std::max(eps, std::max(ra.spacing, rb.spacing));
    // Side k (+e0, -e0, +e1, -e1): its unit direction out of the window; its
    // plane's outward normal is the opposite (it faces into the window).
    const std::array<Vec3, 4> sideAxis{e0, -e0, e1, -e1};
    // How far the point at d from the first rim's centre lies beyond each
    // side (negative inside it); the largest is how far it lies outside the
    // window.
    const auto beyond = [&](const Vec3& d) {
      const double x = d.dot(e0), y = d.dot(e1);
      return std::array<double, 4>{x - hi.x(), lo.x() - x, y - hi.y(), lo.y() - y};
    };
    const auto outside = [&](const Vec3& d) {
      const std::array<double, 4> b = beyond(d);
      return *std::max_element(b.begin(), b.end());
    };
    // The side of the window whose own point the point i at d may be: the
    // first side k into which its normal points (across the axis) with
    // accept(beyond(d)[k]), lying along it (less than `slack` beyond the
    // other two sides); -1 for none.
    const auto sideOf = [&](std::size_t i, const Vec3& d, double slack, const auto& accept) {
      const std::array<double, 4> b = beyond(d);
      for (std::size_t k = 0; k < 4; ++k) {
        const std::size_t o = k < 2 ? 2 : 0;  // the other two sides
        if (b[o] < slack && b[o + 1] < slack && cloud.normals[i].dot(sideAxis[k]) < -kAcrossAxis &&
            accept(b[k])) {
          return int(k);
        }
      }
      return -1;
    };
    const auto between = [&](std::size_t i, const Vec3& d) {
      const double t = -d.dot(n);
      return result.assignment[i] < 0 && t > eps && t < depth - eps;
    };
    // A side whose own points the scan holds lies at their median: a face
    // loses points along its edges (blended normals, depth edges), so its
    // gap reaches past the side. Its points lie within three spacings inside
    // it or one outside.
    {
      std::array<std::vector<double>, 4> at;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Vec3 d = cloud.points[i] - ra.center;
        if (!between(i, d)) continue;
        const auto near = [&](double off) { return off >= -3.0 * band && off <= band; };
        const int k = sideOf(i, d, 0.0, near);
        if (k >= 0) at[std::size_t(k)].push_back(beyond(d)[std::size_t(k)]);
      }
      std::array<double, 4> shift{};
      for (std::size_t k = 0; k < 4; ++k) {
        if (at[k].size() >= kMinEvidence) shift[k] = median(std::move(at[k]));
      }
      if (hi.x() + shift[0] > lo.x() - shift[1] && hi.y() + shift[2] > lo.y() - shift[3]) {
        hi.x() += shift[0];
        lo.x() -= shift[1];
        hi.y() += shift[2];
        lo.y() -= shift[3];
      }
    }
    // The rims' points go to the side they lie beyond.
    std::array<std::vector<std::uint32_t>, 4> sidePoints;
    for (const Rim* rim : {&ra, &rb}) {
      for (std::uint32_t i : rim->points) {
        const std::array<double, 4> b = beyond(cloud.points[i] - ra.center);
        sidePoints[std::size_t(std::max_element(b.begin(), b.end()) - b.begin())].push_back(i);
      }
    }
    // Points inside the window between the faces, and each side's own points
    // (within a spacing or epsilon of it).
    std::size_t inside = 0, wallCount = 0;
    std::array<std::vector<std::uint32_t>, 4> wall;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Vec3 d = cloud.points[i] - ra.center;
      const double t = -d.dot(n);
      if (t < -eps || t > depth + eps) continue;
      const double out = outside(d);
      if (out < -band && t > eps && t < depth - eps) ++inside;
      if (result.assignment[i] >= 0 || std::abs(out) > band) continue;
      if (std::abs(cloud.normals[i].dot(n)) > kAcrossAxis) continue;
      // (Within band of the window, so at most band beyond the other sides.)
      const auto on = [&](double off) { return std::abs(off) <= band; };
      const int k = sideOf(i, d, std::numeric_limits<double>::infinity(), on);
      if (k >= 0) {
        wall[std::size_t(k)].push_back(std::uint32_t(i));
        ++wallCount;
      }
    }
    if (inside > kMinEvidence + wallCount / 10) continue;
    // A bar standing through the wall: its top shows above one of the two
    // faces, inside the window, at one height with no face at that height
    // around it.
    const double halfWidth = 0.5 * (hi.y() - lo.y());  // across the rims' longer side
    const auto capped = [&](const Vec3& faceCenter, const Vec3& faceNormal) {
      std::vector<double> capHeights, aroundHeights;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Vec3 d = cloud.points[i] - faceCenter;
        const double t = -d.dot(faceNormal);
        if (t >= -eps || cloud.normals[i].dot(faceNormal) < kFacing) continue;
        const double out = outside(d);
        if (out < -band) capHeights.push_back(t);
        if (out > 2.0 * band && out < halfWidth) aroundHeights.push_back(t);
      }
      return isCap(capHeights, aroundHeights, eps);
    };
    if (capped(ra.center, n) || capped(ra.center - depth * n, rb.normal)) continue;
    used[a] = used[partner] = 1;
    // The sides' planes (through the point of side k on the axis of the
    // first rim); a side whose plane detection found already keeps it.
    const std::array<double, 4> place{hi.x(), -lo.x(), hi.y(), -lo.y()};
    std::array<PlaneSurface, 4> planes;
    std::array<bool, 4> missing{};
    for (std::size_t k = 0; k < 4; ++k) {
      const Vec3 normal = -sideAxis[k];
      planes[k] = PlaneSurface{normal, normal.dot(ra.center + place[k] * sideAxis[k])};
      missing[k] =
          std::none_of(result.surfaces.begin(), result.surfaces.begin() + std::ptrdiff_t(detected),
                       [&](const Surface& s) {
                         const auto* p = s.as<PlaneSurface>();
                         return p != nullptr && p->normal.dot(normal) > kParallel &&
                                std::abs(p->offset - planes[k].offset) <= 2.0 * eps + band;
                       });
    }
    if (std::none_of(missing.begin(), missing.end(), [](bool m) { return m; })) {
      ++stats.explained;
      continue;
    }
    for (std::size_t k = 0; k < 4; ++k) {
      if (!missing[k]) continue;
      Surface side;
      side.shape = planes[k];
      side.rms = std::max(result.noise, 1e-9 * result.diagonal);
      std::vector<std::uint32_t> points = sidePoints[k];
      points.insert(points.end(), wall[k].begin(), wall[k].end());
      std::sort(points.begin(), points.end());
      points.erase(std::unique(points.begin(), points.end()), points.end());
      const int index = int(result.surfaces.size());
      for (std::uint32_t i : wall[k]) result.assignment[i] = index;
      Vec3 sum = Vec3::Zero();
      for (std::uint32_t i : points) sum += cloud.points[i];
      if (result.centroids.size() == result.surfaces.size()) {
        result.centroids.push_back(sum / double(std::max<std::size_t>(1, points.size())));
      }
      side.inliers = std::move(points);
      result.surfaces.push_back(std::move(side));
    }
    ++stats.windows;
  }
}

}  // namespace

RimHoleStats addRimHoles(const PointCloud& cloud, DetectionResult& result,
                         const RimHoleOptions& options) {
  RimHoleStats stats;
  if (!result.ok() || result.surfaces.empty() || cloud.empty()) return stats;
  std::vector<Rim> rims;
  const std::size_t found = result.surfaces.size();
  std::vector<char> grouped(found, 0);
  std::vector<std::uint32_t> unassigned;  // the points no surface holds
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (result.assignment[i] < 0) unassigned.push_back(std::uint32_t(i));
  }
  for (std::size_t s = 0; s < found; ++s) {
    const auto* p = result.surfaces[s].as<PlaneSurface>();
    if (p == nullptr || grouped[s]) continue;
    std::vector<std::size_t> group;
    for (std::size_t t = s; t < found; ++t) {
      const auto* q = result.surfaces[t].as<PlaneSurface>();
      if (q == nullptr || grouped[t] || p->normal.dot(q->normal) < kCoplanar ||
          std::abs(p->offset - q->offset) > 2.0 * result.epsilon) {
        continue;
      }
      grouped[t] = 1;
      group.push_back(t);
    }
    findRims(cloud, result, group, unassigned, options, rims, stats);
  }
  if (rims.empty()) return stats;
  std::vector<char> used(rims.size(), 0);
  for (std::size_t a = 0; a < rims.size(); ++a) {
    if (!rims[a].window && explained(result, rims[a])) {
      used[a] = 1;
      ++stats.explained;
    }
  }
  const double eps = result.epsilon;
  const Aabb bounds = cloud.bounds();
  for (std::size_t a = 0; a < rims.size(); ++a) {
    if (used[a] || rims[a].window) continue;
    const Rim& ra = rims[a];
    const Vec3 n = ra.normal;
    // How deep the part reaches behind the face, along -n.
    double reach = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? bounds.max.x() : bounds.min.x(),
                   (corner & 2) ? bounds.max.y() : bounds.min.y(),
                   (corner & 4) ? bounds.max.z() : bounds.min.z());
      reach = std::max(reach, (ra.center - p).dot(n));
    }
    std::vector<std::uint32_t> evidence = ra.points;
    double depth = -1.0;  // of the hole's known bottom, or -1
    Vec3 center = ra.center;
    double radius = ra.radius;
    // The same gap in the opposite face: a through hole.
    std::size_t partner = rims.size();
    double partnerDepth = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < rims.size(); ++b) {
      if (used[b] || b == a || rims[b].window || rims[b].normal.dot(n) > -kParallel) continue;
      const Rim& rb = rims[b];
      const Vec3 d = rb.center - ra.center;
      const double along = -d.dot(n);
      const double tolerance = std::max(0.25 * std::min(ra.radius, rb.radius), 2.0 * eps);
      if (along <= eps || lateral(d, n).norm() > tolerance) continue;
      if (std::max(ra.radius, rb.radius) > 1.4 * std::min(ra.radius, rb.radius)) continue;
      if (along < partnerDepth) partnerDepth = along, partner = b;
    }
    if (partner < rims.size()) {
      const Rim& rb = rims[partner];
      used[partner] = 1;
      depth = partnerDepth;
      evidence.insert(evidence.end(), rb.points.begin(), rb.points.end());
      const double wa = double(ra.points.size()), wb = double(rb.points.size());
      radius = (wa * ra.radius + wb * rb.radius) / (wa + wb);
      center = ra.center + wb / (wa + wb) * lateral(rb.center - ra.center, n);
    } else {
      // A face that looks the same way, seen through the gap: the hole's
      // bottom (a blind hole's floor, a counterbore's step).
      std::vector<std::uint32_t> floor;
      for (std::size_t s = 0; s < found; ++s) {
        const auto* p = result.surfaces[s].as<PlaneSurface>();
        if (p == nullptr || s == ra.plane || p->normal.dot(n) < kParallel) continue;
        // (Planes within two epsilon of the face are pieces of it.)
        const double below = ra.center.dot(p->normal) - p->offset;
        if (below <= 2.0 * eps || (depth >= 0.0 && below >= depth)) continue;
        std::vector<std::uint32_t> inside;
        for (std::uint32_t i : result.surfaces[s].inliers) {
          if (lateral(cloud.points[i] - ra.center, n).norm() <= ra.radius) inside.push_back(i);
        }
        if (inside.size() < kMinEvidence) continue;
        depth = below;
        floor = std::move(inside);
      }
      evidence.insert(evidence.end(), floor.begin(), floor.end());
    }
    // The wall's own points that no surface holds (their normals across
    // the axis: a face below, under a boss whose top is the gap, is no
    // wall), and the points inside the hole, of which there should be none
    // between its ends: a gap where a small boss stands on the face (the
    // boss not detected) has the face under it, or the boss's own points.
    const double band = std::max(eps, ra.spacing);
    const double deepest = depth >= 0.0 ? depth + eps : reach;
    std::vector<std::uint32_t> wall;
    double wallDepth = 0.0;
    std::size_t inside = 0;
    // Faces looking the face's way above it: within the circle (a cap) and
    // around it out to twice its radius.
    std::vector<double> capHeights, aroundHeights;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Vec3 d = cloud.points[i] - center;
      const double t = -d.dot(n);
      // Above the face only the points facing its way count.
      if (t > deepest || (t < -eps && cloud.normals[i].dot(n) < kFacing)) continue;
      const double rho = lateral(d, n).norm();
      if (t < -eps) {
        if (rho < radius - band) capHeights.push_back(t);
        if (rho > radius + 2.0 * band && rho < 2.0 * radius) aroundHeights.push_back(t);
        continue;
      }
      if (rho < radius - band && t > eps && (depth < 0.0 || t < depth - eps)) ++inside;
      if (result.assignment[i] >= 0 || std::abs(rho - radius) > band) continue;
      if (std::abs(cloud.normals[i].dot(n)) > kAcrossAxis) continue;
      wall.push_back(std::uint32_t(i));
      wallDepth = std::max(wallDepth, t);
    }
    if (inside > kMinEvidence + wall.size() / 10) continue;
    // A boss standing through the face (a rod whose side no surface holds)
    // leaves the same gap, with nothing inside it below the face; its top
    // shows above the gap: a cap of points facing the face's way, at one
    // height, with no face at that height around it (a face above the hole
    // that reaches past it, as an overhang's would, is no cap).
    if (isCap(capHeights, aroundHeights, eps)) continue;
    if (depth < 0.0 && (wall.size() < kMinEvidence || wallDepth <= 2.0 * eps)) continue;
    used[a] = 1;
    Surface hole;
    hole.shape = CylinderSurface{center, n, radius};
    hole.convex = false;
    hole.rms = std::max(result.noise, 1e-9 * result.diagonal);
    evidence.insert(evidence.end(), wall.begin(), wall.end());
    std::sort(evidence.begin(), evidence.end());
    evidence.erase(std::unique(evidence.begin(), evidence.end()), evidence.end());
    hole.inliers = std::move(evidence);
    const int index = int(result.surfaces.size());
    for (std::uint32_t i : wall) result.assignment[i] = index;
    Vec3 sum = Vec3::Zero();
    for (std::uint32_t i : hole.inliers) sum += cloud.points[i];
    if (result.centroids.size() == result.surfaces.size()) {
      result.centroids.push_back(sum / double(hole.inliers.size()));
    }
    result.surfaces.push_back(std::move(hole));
    ++stats.holes;
  }
  addWindows(cloud, rims, used, result, stats);
  return stats;
}

}  // namespace csgvox
