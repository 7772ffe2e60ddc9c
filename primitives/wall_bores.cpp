#include "primitives/wall_bores.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "core/nearest_neighbors.h"
#include "core/union_find.h"
#include "primitives/surface_fit.h"

namespace csgvox {

namespace {

using Vec2 = Eigen::Vector2d;

// Two directions are one when their lines make less than about 3 degrees.
constexpr double kSameDirection = 0.9986;
// Directions searched are at least about 10 degrees apart: a cone or torus
// fitted a little askew would find the bores of a direction again.
constexpr double kDistinctDirections = 0.985;
// A free point within epsilon of a surface found lies on it, unless its
// normal crosses the surface (about 65 degrees or more: the wall of a hole
// meets its face) — normals blended at an edge lie within 45 degrees.
constexpr double kCrossingCosine = 0.42;
// Neighbours among which the second point of a pair is drawn.
constexpr std::size_t kPairNeighbours = 16;
// Two normals of a pair must make at least this angle (sine, about 6
// degrees): nearly parallel lines meet far from where they are known.
constexpr double kMinCrossing = 0.1;
// Pairs tried per round: this many per expected draw of a bore's point
// (candidates / least support), within the bounds below.
constexpr double kDrawsPerBore = 40.0;
constexpr std::size_t kMinTries = 500;
constexpr std::size_t kMaxTries = 20000;
// The widest gap within a wall's arc: the cluster distance as an angle,
// within these bounds (radians: 15 and 45 degrees).
constexpr double kMinArcGap = 0.2617993877991494;
constexpr double kMaxArcGap = 0.7853981633974483;
// Points inside a bore between its ends, beyond its wall's band: at most
// this many plus a tenth of its wall's.
constexpr std::size_t kInsideAllowance = 4;

// A direction the part shows, with the points of the surfaces that show it.
struct Direction {
  Vec3 d;
  double weight;
};

// The directions of `surfaces` (plane normals, axes), heaviest first.
std::vector<Direction> partDirections(const std::vector<Surface>& surfaces) {
  std::vector<Direction> found;
  for (const Surface& s : surfaces) {
    const std::optional<Vec3> direction = surfaceDirection(s);
    if (!direction) continue;
    const Vec3 d = *direction;
    const double w = double(s.inliers.size());
    auto same = std::find_if(found.begin(), found.end(), [&](const Direction& f) {
      return std::abs(f.d.dot(d)) > kSameDirection;
    });
    if (same == found.end()) {
      found.push_back({d, w});
    } else if (w > same->weight) {
      // The direction of the heaviest surface that shows it.
      same->d = same->d.dot(d) < 0.0 ? Vec3(-d) : d;
      same->weight += w;
    } else {
      same->weight += w;
    }
  }
  std::stable_sort(found.begin(), found.end(),
                   [](const Direction& a, const Direction& b) { return a.weight > b.weight; });
  std::vector<Direction> distinct;
  for (const Direction& f : found) {
    if (std::none_of(distinct.begin(), distinct.end(), [&](const Direction& g) {
          return std::abs(g.d.dot(f.d)) > kDistinctDirections;
        })) {
      distinct.push_back(f);
    }
  }
  return distinct;
}

// The unassigned points whose normals lie across one direction, projected
// onto the plane across it, with a grid for annulus queries.
struct Section {
  Vec3 d, u, v;
  std::vector<std::uint32_t> index;  // into the cloud
  std::vector<Vec2> q;               // projected positions
  std::vector<Vec2> m;               // projected unit normals
  std::vector<double> t;             // positions along d
  double cell = 1.0;
  Vec2 origin = Vec2::Zero();
  int nx = 1, ny = 1;
  std::vector<std::uint32_t> start;  // per cell, into order
  std::vector<std::uint32_t> order;  // section indices, by cell

  int cellX(double x) const {
    return std::clamp(int(std::floor((x - origin.x()) / cell)), 0, nx - 1);
  }
  int cellY(double y) const {
    return std::clamp(int(std::floor((y - origin.y()) / cell)), 0, ny - 1);
  }

  void buildGrid(double cellSize) {
    cell = cellSize;
    Vec2 lo = q.front(), hi = q.front();
    for (const Vec2& p : q) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    origin = lo;
    nx = std::max(1, int(std::ceil((hi.x() - lo.x()) / cell)) + 1);
    ny = std::max(1, int(std::ceil((hi.y() - lo.y()) / cell)) + 1);
    start.assign(std::size_t(nx) * std::size_t(ny) + 1, 0);
    std::vector<std::uint32_t> cellOf(q.size());
    for (std::size_t i = 0; i < q.size(); ++i) {
      cellOf[i] = std::uint32_t(cellY(q[i].y()) * nx + cellX(q[i].x()));
      ++start[cellOf[i] + 1];
    }
    for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
    order.assign(q.size(), 0);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < q.size(); ++i) order[fill[cellOf[i]]++] = std::uint32_t(i);
  }

  // Calls f(i) for every section point within the square around c of half
  // side `reach`.
  template <class F>
  void around(const Vec2& c, double reach, F&& f) const {
    const int x0 = cellX(c.x() - reach), x1 = cellX(c.x() + reach);
    const int y0 = cellY(c.y() - reach), y1 = cellY(c.y() + reach);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const std::size_t cIndex = std::size_t(y) * std::size_t(nx) + std::size_t(x);
        for (std::uint32_t k = start[cIndex]; k < start[cIndex + 1]; ++k) f(order[k]);
      }
    }
  }
};

// A circle on a section: its wall's normals point to the centre (side +1,
// a hole) or away from it (side -1, a boss).
struct Circle {
  Vec2 c = Vec2::Zero();
  double r = 0.0;
  int side = 0;
};

// Calls f(i) for each section point on `circle` (within eps, normals within
// the threshold of the radial direction on its side) that is still free.
template <class F>
void forEachOnCircle(const Section& s, const Circle& circle, double eps, double cosine,
                     const std::vector<char>& taken, F&& f) {
  s.around(circle.c, circle.r + eps, [&](std::uint32_t i) {
    if (taken[i]) return;
    const Vec2 to = circle.c - s.q[i];
    const double rho = to.norm();
    if (std::abs(rho - circle.r) > eps || !(rho > 0.0)) return;
    if (double(circle.side) * s.m[i].dot(to) / rho < cosine) return;
    f(i);
  });
}

// The section points on `circle` that are still free, in index order.
std::vector<std::uint32_t> onCircle(const Section& s, const Circle& circle, double eps,
                                    double cosine, const std::vector<char>& taken) {
  std::vector<std::uint32_t> on;
  forEachOnCircle(s, circle, eps, cosine, taken, [&](std::uint32_t i) { on.push_back(i); });
  std::sort(on.begin(), on.end());
  return on;
}

// The circle of two points and their normals, or none.
bool circleOfPair(const Section& s, std::uint32_t i, std::uint32_t j, double eps, double rMin,
                  double rMax, Circle& out) {
  const Vec2 &a = s.q[i], &b = s.q[j], &na = s.m[i], &nb = s.m[j];
  const double cross = na.x() * nb.y() - na.y() * nb.x();
  if (std::abs(cross) < kMinCrossing) return false;
  // a + ta na = b + tb nb.
  const Vec2 ab = b - a;
  const double ta = (ab.x() * nb.y() - ab.y() * nb.x()) / cross;
  const double tb = (ab.x() * na.y() - ab.y() * na.x()) / cross;
  if ((ta > 0.0) != (tb > 0.0)) return false;
  const double ra = std::abs(ta), rb = std::abs(tb);
  if (std::abs(ra - rb) > eps) return false;
  out.r = 0.5 * (ra + rb);
  if (out.r < rMin || out.r > rMax) return false;
  out.c = 0.5 * ((a + ta * na) + (b + tb * nb));
  out.side = ta > 0.0 ? 1 : -1;
  return true;
}

// The least-squares circle through `on` (Kåsa), or false when degenerate.
bool refitCircle(const Section& s, const std::vector<std::uint32_t>& on, Circle& circle) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  const Vec2 o = circle.c;  // centred for conditioning
  for (std::uint32_t i : on) {
    const Vec2 p = s.q[i] - o;
    const Eigen::Vector3d row(p.x(), p.y(), 1.0);
    A += row * row.transpose();
    b -= row * p.squaredNorm();
  }
  const Eigen::Vector3d x = A.ldlt().solve(b);
  if (!x.allFinite()) return false;
  const Vec2 c(-0.5 * x[0], -0.5 * x[1]);
  const double r2 = c.squaredNorm() - x[2];
  if (!(r2 > 0.0)) return false;
  circle.c = o + c;
  circle.r = std::sqrt(r2);
  return true;
}

// The widest angle around the centre that the points cover without a gap
// wider than `maxGap` (radians): two strips on opposite sides of a circle
// (two parallel faces) cover little each.
double arcCovered(const Section& s, const std::vector<std::uint32_t>& on, const Vec2& c,
                  double maxGap) {
  if (on.size() < 2) return 0.0;
  std::vector<double> angle;
  angle.reserve(on.size());
  for (std::uint32_t i : on) {
    const Vec2 p = s.q[i] - c;
    angle.push_back(std::atan2(p.y(), p.x()));
  }
  std::sort(angle.begin(), angle.end());
  const std::size_t n = angle.size();
  // Gaps after each angle, the last one across the turn.
  std::vector<double> gap(n);
  for (std::size_t k = 0; k + 1 < n; ++k) gap[k] = angle[k + 1] - angle[k];
  gap[n - 1] = angle.front() + 2.0 * std::numbers::pi - angle.back();
  std::size_t wide = n;  // a gap wider than maxGap, where runs start after
  for (std::size_t k = 0; k < n; ++k) {
    if (gap[k] > maxGap) {
      wide = k;
      break;
    }
  }
  if (wide == n) return 2.0 * std::numbers::pi;
  double best = 0.0, run = 0.0;
  for (std::size_t step = 1; step <= n; ++step) {
    const std::size_t k = (wide + step) % n;
    if (gap[k] > maxGap) {
      best = std::max(best, run);
      run = 0.0;
    } else {
      run += gap[k];
    }
  }
  return std::max(best, run);
}

// The largest run of `on` along the axis with no gap wider than `link`.
std::vector<std::uint32_t> largestRun(const Section& s, std::vector<std::uint32_t> on,
                                      double link) {
  std::sort(on.begin(), on.end(), [&](std::uint32_t a, std::uint32_t b) {
    return s.t[a] < s.t[b] || (s.t[a] == s.t[b] && a < b);
  });
  std::size_t bestStart = 0, bestLength = 0;
  for (std::size_t k = 0; k < on.size();) {
    std::size_t e = k + 1;
    while (e < on.size() && s.t[on[e]] - s.t[on[e - 1]] <= link) ++e;
    if (e - k > bestLength) bestStart = k, bestLength = e - k;
    k = e;
  }
  std::vector<std::uint32_t> run(on.begin() + std::ptrdiff_t(bestStart),
                                 on.begin() + std::ptrdiff_t(bestStart + bestLength));
  std::sort(run.begin(), run.end());
  return run;
}

// A cylinder of `surfaces` that is this one: the same line within a few
// epsilon and the same radius.
bool duplicates(const std::vector<Surface>& surfaces, const Vec3& point, const Vec3& d, double r,
                double eps) {
  for (const Surface& s : surfaces) {
    const auto* c = s.as<CylinderSurface>();
    if (c == nullptr || std::abs(c->axisDir.normalized().dot(d)) < kSameDirection) continue;
    const Vec3 off = point - c->axisPoint;
    const double lateral = (off - off.dot(d) * d).norm();
    if (lateral <= 2.0 * eps && std::abs(c->radius - r) <= 2.0 * eps) return true;
  }
  return false;
}

// Free points that a surface found explains lie on it (left out of its
// patch, or a strip of normals blended at its edge), not on a wall of
// their own.
std::vector<char> explainedFreePoints(const PointCloud& cloud, const DetectionResult& result) {
  std::vector<char> explained(cloud.size(), 0);
  tbb::parallel_for(std::size_t{0}, cloud.size(), [&](std::size_t i) {
    if (result.assignment[i] >= 0) return;
    for (const Surface& surface : result.surfaces) {
      if (surfaceDistance(surface, cloud.points[i]) <= result.epsilon &&
          std::abs(surfaceNormal(surface, cloud.points[i]).dot(cloud.normals[i])) >=
              kCrossingCosine) {
        explained[i] = 1;
        return;
      }
    }
  });
  return explained;
}

// The largest set of `points` linked by steps shorter than `link` (between
// each point and its 16 nearest; `nn` holds `points`), as indices into
// `points`.
std::vector<std::uint32_t> largestCluster(const std::vector<Vec3>& points,
                                          const NearestNeighbors& nn, double link) {
  if (points.empty()) return {};
  std::vector<std::uint32_t> parent(points.size());
  for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  std::vector<std::uint32_t> near;
  std::vector<double> d2;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    nn.kNearest(points[i], kPairNeighbours + 1, near, &d2);
    for (std::size_t k = 0; k < near.size(); ++k) {
      if (d2[k] > link * link) break;
      const std::uint32_t a = findRoot(parent, i), b = findRoot(parent, near[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<std::uint32_t> size(points.size(), 0);
  for (std::uint32_t i = 0; i < points.size(); ++i) ++size[findRoot(parent, i)];
  const std::uint32_t root =
      std::uint32_t(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<std::uint32_t> members;
  for (std::uint32_t i = 0; i < points.size(); ++i)
    if (findRoot(parent, i) == root) members.push_back(i);
  return members;
}

}  // namespace

WallBoreStats addWallBores(const PointCloud& cloud, DetectionResult& result,
                           const WallBoreOptions& options) {
  WallBoreStats stats;
  if (!result.ok() || cloud.size() != result.assignment.size() || !cloud.hasNormals()) {
    return stats;
  }
  const double eps = result.epsilon;
  const double diag = result.diagonal;
  const double cosine = result.normalThreshold;
  const double across = std::sqrt(std::max(0.0, 1.0 - cosine * cosine));
  const double rMin = options.minRadiusEpsilons * eps;
  const double rMax = options.maxRadius * diag;
  const std::size_t least = std::max<std::size_t>(result.minPoints, 3);
  const double link = std::max(result.clusterEpsilon, eps);
  if (!(eps > 0.0) || !(rMax > rMin)) return stats;

  const std::vector<char> explained = explainedFreePoints(cloud, result);
  std::vector<Direction> directions = partDirections(result.surfaces);
  if (directions.size() > options.maxDirections) directions.resize(options.maxDirections);
  std::mt19937_64 rng(options.seed);
  for (const Direction& dir : directions) {
    if (stats.bores >= options.maxBores) break;
    ++stats.directions;
    Section s;
    s.d = dir.d;
    s.u = s.d.unitOrthogonal();
    s.v = s.d.cross(s.u);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (result.assignment[i] >= 0 || explained[i]) continue;
      const Vec3& n = cloud.normals[i];
      if (std::abs(n.dot(s.d)) > across) continue;
      const Vec2 m(n.dot(s.u), n.dot(s.v));
      if (!(m.norm() > 0.0)) continue;
      const Vec3& p = cloud.points[i];
      s.index.push_back(std::uint32_t(i));
      s.q.emplace_back(p.dot(s.u), p.dot(s.v));
      s.m.push_back(m.normalized());
      s.t.push_back(p.dot(s.d));
    }
    if (s.index.size() < least) continue;
    s.buildGrid(std::max(4.0 * eps, rMax / 8.0));
    std::vector<Vec3> positions;
    positions.reserve(s.index.size());
    for (std::uint32_t i : s.index) positions.push_back(cloud.points[i]);
    const NearestNeighbors nn(positions);
    std::vector<char> taken(s.index.size(), 0);
    std::vector<std::uint32_t> near;
    for (;;) {
      if (stats.bores >= options.maxBores) break;
      std::vector<std::uint32_t> free;
      for (std::uint32_t i = 0; i < s.index.size(); ++i) {
        if (!taken[i]) free.push_back(i);
      }
      if (free.size() < least) break;
      const std::size_t tries = std::clamp<std::size_t>(
          std::size_t(kDrawsPerBore * double(free.size()) / double(least)), kMinTries, kMaxTries);
      Circle best;
      std::size_t bestCount = 0;
      std::uniform_int_distribution<std::size_t> pick(0, free.size() - 1);
      for (std::size_t attempt = 0; attempt < tries; ++attempt) {
        const std::uint32_t i = free[pick(rng)];
        nn.kNearest(positions[i], kPairNeighbours + 1, near);
        const std::uint32_t j = near[std::uniform_int_distribution<std::size_t>(
            near.size() > 1 ? 1 : 0, near.size() - 1)(rng)];
        if (j == i || taken[j]) continue;
        Circle circle;
        if (!circleOfPair(s, i, j, eps, rMin, rMax, circle)) continue;
        // Counted only: the pairs tried are many, the circle kept is one.
        std::size_t count = 0;
        forEachOnCircle(s, circle, eps, cosine, taken, [&](std::uint32_t) { ++count; });
        if (count > bestCount) bestCount = count, best = circle;
      }
      if (bestCount < least) break;
      ++stats.tried;
      // Refined on its points, then cut to its longest run along the axis.
      std::vector<std::uint32_t> on = onCircle(s, best, eps, cosine, taken);
      Circle refit = best;
      if (refitCircle(s, on, refit) && refit.r >= rMin && refit.r <= rMax) {
        std::vector<std::uint32_t> again = onCircle(s, refit, eps, cosine, taken);
        if (again.size() >= on.size()) best = refit, on = std::move(again);
      }
      on = largestRun(s, std::move(on), link);
      // Whatever the verdict, these points are not tried again along this
      // direction.
      const auto markTaken = [&](const std::vector<std::uint32_t>& points) {
        for (std::uint32_t i : points) taken[i] = 1;
      };
      if (on.size() < least) {
        markTaken(on);
        continue;
      }
      const double maxGap = std::clamp(link / best.r, kMinArcGap, kMaxArcGap);
      if (arcCovered(s, on, best.c, maxGap) < options.minArc) {
        markTaken(on);
        continue;
      }
      double t0 = std::numeric_limits<double>::infinity(), t1 = -t0;
      for (std::uint32_t i : on) t0 = std::min(t0, s.t[i]), t1 = std::max(t1, s.t[i]);
      const Vec3 axisPoint = best.c.x() * s.u + best.c.y() * s.v + 0.5 * (t0 + t1) * s.d;
      if (duplicates(result.surfaces, axisPoint, s.d, best.r, eps)) {
        markTaken(on);
        continue;
      }
      // No surface inside a bore between its ends (nor inside a boss).
      std::size_t inside = 0;
      const double band = std::max(eps, 0.1 * best.r);
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Vec3& p = cloud.points[i];
        const double t = p.dot(s.d);
        if (t <= t0 + eps || t >= t1 - eps) continue;
        if ((Vec2(p.dot(s.u), p.dot(s.v)) - best.c).norm() < best.r - band) ++inside;
      }
      if (inside > kInsideAllowance + on.size() / 10) {
        markTaken(on);
        continue;
      }
      Surface bore;
      bore.shape = CylinderSurface{axisPoint, s.d, best.r};
      bore.convex = best.side < 0;
      double sum = 0.0;
      Vec3 centroid = Vec3::Zero();
      for (std::uint32_t i : on) {
        const double e = (best.c - s.q[i]).norm() - best.r;
        sum += e * e;
        bore.inliers.push_back(s.index[i]);
        centroid += cloud.points[s.index[i]];
      }
      bore.rms = std::max(std::sqrt(sum / double(on.size())), 1e-9 * diag);
      std::sort(bore.inliers.begin(), bore.inliers.end());
      const int index = int(result.surfaces.size());
      for (std::uint32_t i : bore.inliers) result.assignment[i] = index;
      if (result.centroids.size() == result.surfaces.size()) {
        result.centroids.push_back(centroid / double(on.size()));
      }
      result.surfaces.push_back(std::move(bore));
      markTaken(on);
      ++stats.bores;
    }
  }
  return stats;
}

// A face's points are those whose normals lie within 60 degrees of it:
// normals blended across a narrow face's edges by the neighbourhoods.
constexpr double kFaceCosine = 0.5;

WallPlaneStats addWallPlanes(const PointCloud& cloud, DetectionResult& result,
                             const WallPlaneOptions& options) {
  WallPlaneStats stats;
  if (!result.ok() || cloud.size() != result.assignment.size() || !cloud.hasNormals()) {
    return stats;
  }
  const double eps = result.epsilon;
  const std::size_t least = std::max<std::size_t>(result.minPoints, 3);
  const double link = std::max(result.clusterEpsilon, eps);
  if (!(eps > 0.0)) return stats;
  const std::vector<char> explained = explainedFreePoints(cloud, result);
  std::vector<Direction> directions = partDirections(result.surfaces);
  if (directions.size() > options.maxDirections) directions.resize(options.maxDirections);
  for (const Direction& dir : directions) {
    for (const double side : {1.0, -1.0}) {
      if (stats.planes >= options.maxPlanes) break;
      ++stats.directions;
      const Vec3 normal = side * dir.d;
      // The free points facing along `normal`, by their position along it.
      std::vector<std::pair<double, std::uint32_t>> along;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (result.assignment[i] >= 0 || explained[i]) continue;
        if (cloud.normals[i].dot(normal) < kFaceCosine) continue;
        along.emplace_back(cloud.points[i].dot(normal), std::uint32_t(i));
      }
      std::sort(along.begin(), along.end());
      // The points (of `along`) of the windows tried on this side, whatever
      // the verdict (a face added takes its points from the others too).
      std::vector<char> taken(along.size(), 0);
      for (;;) {
        if (stats.planes >= options.maxPlanes) break;
        // The densest window 2 epsilon wide among the points not yet taken
        // (counted by a running sum of them).
        std::vector<std::size_t> untaken(along.size() + 1, 0);
        for (std::size_t k = 0; k < along.size(); ++k) untaken[k + 1] = untaken[k] + !taken[k];
        std::size_t bestLo = 0, bestCount = 0;
        for (std::size_t lo = 0, hi = 0; lo < along.size(); ++lo) {
          if (taken[lo]) continue;
          hi = std::max(hi, lo);
          while (hi < along.size() && along[hi].first <= along[lo].first + 2.0 * eps) ++hi;
          const std::size_t count = untaken[hi] - untaken[lo];
          if (count > bestCount) bestCount = count, bestLo = lo;
        }
        if (bestCount < least) break;
        std::vector<std::uint32_t> window;
        for (std::size_t k = bestLo;
             k < along.size() && along[k].first <= along[bestLo].first + 2.0 * eps; ++k) {
          if (taken[k]) continue;
          taken[k] = 1;
          window.push_back(along[k].second);
        }
        ++stats.tried;
        // Its largest connected patch.
        std::vector<Vec3> positions;
        for (std::uint32_t i : window) positions.push_back(cloud.points[i]);
        const NearestNeighbors nn(positions);
        const double reach =
            std::max(link, options.spacingFactor * medianNearestDistance(positions, nn));
        const std::vector<std::uint32_t> patch = largestCluster(positions, nn, reach);
        if (patch.size() < least) continue;
        std::vector<std::uint32_t> inliers;
        std::vector<double> t;
        for (std::uint32_t k : patch) {
          inliers.push_back(window[k]);
          t.push_back(cloud.points[window[k]].dot(normal));
        }
        std::nth_element(t.begin(), t.begin() + std::ptrdiff_t(t.size() / 2), t.end());
        const double offset = t[t.size() / 2];
        // Not a plane found already (a face's other patch, or its edge's
        // points a little off it).
        const bool known = std::any_of(
            result.surfaces.begin(), result.surfaces.end(), [&](const Surface& s) {
              const auto* plane = s.as<PlaneSurface>();
              return plane != nullptr && plane->normal.dot(normal) > kSameDirection &&
                     std::abs(plane->offset - offset) < 2.0 * eps;
            });
        if (known) continue;
        Surface face;
        face.shape = PlaneSurface{normal, offset};
        double sum = 0.0;
        Vec3 centroid = Vec3::Zero();
        for (std::uint32_t i : inliers) {
          const double e = cloud.points[i].dot(normal) - offset;
          sum += e * e;
          centroid += cloud.points[i];
        }
        face.rms = std::max(std::sqrt(sum / double(inliers.size())), 1e-9 * result.diagonal);
        std::sort(inliers.begin(), inliers.end());
        face.inliers = std::move(inliers);
        const int index = int(result.surfaces.size());
        for (std::uint32_t i : face.inliers) result.assignment[i] = index;
        if (result.centroids.size() == result.surfaces.size()) {
          result.centroids.push_back(centroid / double(face.inliers.size()));
        }
        result.surfaces.push_back(std::move(face));
        ++stats.planes;
      }
    }
  }
  return stats;
}

}  // namespace csgvox
