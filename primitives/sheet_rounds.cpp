#include "primitives/sheet_rounds.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

#include "core/nearest_neighbors.h"
#include "core/statistics.h"

namespace csgvox {

namespace {

// Two faces are opposite when their normals' dot product is below minus
// this (about 11 degrees), and a round's axis is along (or across) their
// normal within the same angle.
constexpr double kParallel = 0.98;
// A face's points along the round, at least (count).
constexpr std::size_t kMinEvidence = 8;
// A plane tilted this far from a thin sheet's faces (radians), with this
// share of its points inside the sheet's slab, is the sheet's edge.
constexpr double kTiltMin = 5.0 * std::numbers::pi / 180.0;
constexpr double kTiltMax = 35.0 * std::numbers::pi / 180.0;
constexpr double kInSlab = 0.8;
constexpr double kTiltedShare = 0.1;
// Points of a face whose spacing is measured, about.
constexpr std::size_t kSpacingSamples = 2000;

// Two opposite faces of a sheet: `normal` and `offset` are the first's; the
// second lies at -otherOffset along the same normal (its own normal the
// opposite way), so the sheet is the slab -otherOffset <= n.x <= offset.
struct Sheet {
  std::size_t first, second;
  Vec3 normal;
  double offset, otherOffset;
  double thickness() const { return offset + otherOffset; }
  double middle() const { return 0.5 * (offset - otherOffset); }
};

double faceSpacing(const PointCloud& cloud, const Surface& face) {
  std::vector<Vec3> points;
  points.reserve(face.inliers.size());
  for (std::uint32_t i : face.inliers) points.push_back(cloud.points[i]);
  if (points.size() < 2) return 0.0;
  return medianNearestDistance(points, NearestNeighbors(points), kSpacingSamples);
}

// The pairs of opposite faces no more than maxThicknessSpacings spacings of
// their points apart.
std::vector<Sheet> thinSheets(const PointCloud& cloud, const DetectionResult& result,
                              const SheetRoundOptions& options) {
  std::vector<double> spacing(result.surfaces.size(), -1.0);
  std::vector<Sheet> sheets;
  for (std::size_t a = 0; a < result.surfaces.size(); ++a) {
    const auto* p = result.surfaces[a].as<PlaneSurface>();
    if (p == nullptr) continue;
    for (std::size_t b = a + 1; b < result.surfaces.size(); ++b) {
      const auto* q = result.surfaces[b].as<PlaneSurface>();
      if (q == nullptr || p->normal.dot(q->normal) > -kParallel) continue;
      const Sheet sheet{a, b, p->normal, p->offset, q->offset};
      if (!(sheet.thickness() > 0.0)) continue;
      for (std::size_t s : {a, b}) {
        if (spacing[s] < 0.0) spacing[s] = faceSpacing(cloud, result.surfaces[s]);
      }
      const double finer = std::min(spacing[a], spacing[b]);
      if (finer > 0.0 && sheet.thickness() <= options.maxThicknessSpacings * finer) {
        sheets.push_back(sheet);
      }
    }
  }
  return sheets;
}

bool halfThick(double radius, const Sheet& sheet, const SheetRoundOptions& options) {
  return std::abs(2.0 * radius - sheet.thickness()) <= options.tolerance * sheet.thickness();
}

// True when each of the sheet's faces holds kMinEvidence points within
// `reach` of the round (`distance` gives a point's distance from its axis or
// circle).
template <class Distance>
bool bothFacesAlong(const PointCloud& cloud, const DetectionResult& result, const Sheet& sheet,
                    double reach, const Distance& distance) {
  for (std::size_t f : {sheet.first, sheet.second}) {
    std::size_t n = 0;
    for (std::uint32_t i : result.surfaces[f].inliers) {
      n += distance(cloud.points[i]) <= reach ? 1 : 0;
    }
    if (n < kMinEvidence) return false;
  }
  return true;
}

// Distance of p from the cylinder's axis line.
double fromAxis(const CylinderSurface& c, const Vec3& p) {
  const Vec3 v = p - c.axisPoint;
  return (v - v.dot(c.axisDir) * c.axisDir).norm();
}

// Which way along `dir` the sheet's faces' points within `reach` of the
// cylinder's axis lie from it: the sum of their offsets.
double sideOf(const PointCloud& cloud, const DetectionResult& result, const Sheet& sheet,
              const CylinderSurface& c, double reach, const Vec3& dir) {
  double side = 0.0;
  for (std::size_t f : {sheet.first, sheet.second}) {
    for (std::uint32_t i : result.surfaces[f].inliers) {
      const Vec3& q = cloud.points[i];
      if (fromAxis(c, q) <= reach) side += (q - c.axisPoint).dot(dir);
    }
  }
  return side;
}

// True when the cylinder is the blend of the square corner where two thin
// sheets meet at a right angle (an L, a tray's floor and wall): its axis
// along their common edge and inside both slabs, its radius from 15 % of the
// thinner's thickness to 135 % of the thicker's, and points of the scan at the corner's outer line
// itself, within max(3 noise deviations, a quarter of the radius) of it
// along the cylinder's points' span (a real round leaves that line (sqrt 2 -
// 1) times its radius away).
bool inSheetCorner(const PointCloud& cloud, const DetectionResult& result, const Surface& round,
                   const std::vector<Sheet>& sheets, const SheetRoundOptions& options) {
  const auto* c = round.as<CylinderSurface>();
  const Vec3& p = c->axisPoint;
  const Vec3& d = c->axisDir;
  const double tol = options.tolerance;
  for (std::size_t a = 0; a < sheets.size(); ++a) {
    for (std::size_t b = a + 1; b < sheets.size(); ++b) {
      const Sheet& A = sheets[a];
      const Sheet& B = sheets[b];
      if (std::abs(A.normal.dot(B.normal)) > 1.0 - kParallel ||
          std::abs(d.dot(A.normal)) > 1.0 - kParallel ||
          std::abs(d.dot(B.normal)) > 1.0 - kParallel) {
        continue;
      }
      const double ta = A.thickness(), tb = B.thickness();
      if (std::abs(A.normal.dot(p) - A.middle()) > 0.5 * ta ||
          std::abs(B.normal.dot(p) - B.middle()) > 0.5 * tb ||
          c->radius > (1.0 + tol) * std::max(ta, tb) ||
          c->radius < (0.5 - tol) * std::min(ta, tb)) {
        continue;
      }
      // Each sheet's outer face is the one away from the other's body.
      const double reach = c->radius + 2.0 * std::max(ta, tb);
      const auto outerHeight = [&](const Sheet& s, const Sheet& other) {
        return sideOf(cloud, result, other, *c, reach, s.normal) > 0.0 ? -s.otherOffset : s.offset;
      };
      const Vec3 corner = p + (outerHeight(A, B) - A.normal.dot(p)) * A.normal +
                          (outerHeight(B, A) - B.normal.dot(p)) * B.normal;
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (std::uint32_t i : round.inliers) {
        const double t = (cloud.points[i] - p).dot(d);
        lo = std::min(lo, t), hi = std::max(hi, t);
      }
      const double near = std::max(3.0 * result.noise, 0.25 * c->radius);
      std::size_t atCorner = 0;
      const CylinderSurface line{corner, d, 0.0};
      for (const Vec3& q : cloud.points) {
        const double t = (q - p).dot(d);
        if (t >= lo && t <= hi && fromAxis(line, q) <= near) ++atCorner;
      }
      if (atCorner >= kMinEvidence) return true;
    }
  }
  return false;
}

// True when plane `s` is a thin sheet's square edge read as a narrow
// tilted face: its normal within kTiltMin..kTiltMax degrees of the sheet's
// faces', at least kInSlab of its points inside the sheet's slab (within two
// noise deviations), and at most kTiltedShare as many points as the smaller
// face. Normals blended across the edge put such a plane through the strip
// along it.
bool tiltedAtSheetEdge(const PointCloud& cloud, const DetectionResult& result, std::size_t s,
                       const std::vector<Sheet>& sheets, double noise) {
  const auto* p = result.surfaces[s].as<PlaneSurface>();
  if (p == nullptr || result.surfaces[s].inliers.empty()) return false;
  for (const Sheet& sheet : sheets) {
    if (s == sheet.first || s == sheet.second) continue;
    const double c = std::abs(p->normal.dot(sheet.normal));
    if (c > std::cos(kTiltMin) || c < std::cos(kTiltMax)) continue;
    std::size_t inside = 0;
    for (std::uint32_t i : result.surfaces[s].inliers) {
      const double h = sheet.normal.dot(cloud.points[i]);
      inside += (h <= sheet.offset + 2.0 * noise && h >= -sheet.otherOffset - 2.0 * noise) ? 1 : 0;
    }
    const std::size_t smaller = std::min(result.surfaces[sheet.first].inliers.size(),
                                         result.surfaces[sheet.second].inliers.size());
    if (double(inside) >= kInSlab * double(result.surfaces[s].inliers.size()) &&
        double(result.surfaces[s].inliers.size()) <= kTiltedShare * double(smaller)) {
      return true;
    }
  }
  return false;
}

}  // namespace

SheetRoundStats replaceSheetRounds(const PointCloud& cloud, DetectionResult& result,
                                   const SheetRoundOptions& options) {
  SheetRoundStats stats;
  const bool anyRound =
      std::any_of(result.surfaces.begin(), result.surfaces.end(), [](const Surface& s) {
        return s.convex && (s.as<TorusSurface>() != nullptr || s.as<CylinderSurface>() != nullptr);
      });
  const auto planes =
      std::count_if(result.surfaces.begin(), result.surfaces.end(),
                    [](const Surface& s) { return s.as<PlaneSurface>() != nullptr; });
  if (!anyRound && planes < 3) return stats;
  const std::vector<Sheet> sheets = thinSheets(cloud, result, options);
  if (sheets.empty()) return stats;
  const double eps = result.epsilon;
  const double noise = std::max(result.noise, 1e-9 * result.diagonal);
  const std::size_t found = result.surfaces.size();
  std::vector<char> drop(found, 0);
  std::vector<Surface> added;
  for (std::size_t s = 0; s < found; ++s) {
    Surface& round = result.surfaces[s];
    if (!round.convex) continue;
    for (const Sheet& sheet : sheets) {
      const Vec3& n = sheet.normal;
      const double band = options.tolerance * sheet.thickness();
      if (const auto* t = round.as<TorusSurface>()) {
        if (std::abs(t->axisDir.dot(n)) < kParallel || !halfThick(t->minorRadius, sheet, options) ||
            std::abs(t->center.dot(n) - sheet.middle()) > band) {
          continue;
        }
        const auto fromCircle = [&](const Vec3& p) {
          const Vec3 d = p - t->center;
          const double along = d.dot(t->axisDir);
          const double rho = (d - along * t->axisDir).norm();
          return std::hypot(rho - t->majorRadius, along);
        };
        if (!bothFacesAlong(cloud, result, sheet, t->minorRadius + 2.0 * eps, fromCircle)) continue;
        drop[s] = 1;
        ++stats.tori;
        break;
      }
      const auto* c = round.as<CylinderSurface>();
      if (c == nullptr || std::abs(c->axisDir.dot(n)) > 1.0 - kParallel ||
          !halfThick(c->radius, sheet, options) ||
          std::abs(c->axisPoint.dot(n) - sheet.middle()) > band) {
        continue;
      }
      const double reach = c->radius + 2.0 * eps;
      const auto distance = [&](const Vec3& q) { return fromAxis(*c, q); };
      if (!bothFacesAlong(cloud, result, sheet, reach, distance)) continue;
      // The end face looks away from the sheet: from the axis away from the
      // faces' points along it.
      Vec3 m = c->axisDir.cross(n).normalized();
      if (sideOf(cloud, result, sheet, *c, reach, m) > 0.0) m = -m;
      // Its points are the outermost of the cylinder's: the end face's own,
      // or the faces' last ones before the edge.
      std::vector<double> outer;
      std::vector<std::uint32_t> kept;
      for (std::uint32_t i : round.inliers) {
        const double q = (cloud.points[i] - c->axisPoint).dot(m);
        if (q <= 0.0 || result.assignment[i] != int(s)) continue;
        outer.push_back(q);
        kept.push_back(i);
      }
      if (outer.size() < kMinEvidence) continue;
      std::vector<double> top = outer;
      std::nth_element(top.begin(), top.begin() + (kMinEvidence - 1), top.end(), std::greater<>());
      top.resize(kMinEvidence);
      const double end = median(std::move(top));
      const double offset = c->axisPoint.dot(m) + end;
      // The face holds the points at it (its fit and the regularisation
      // place it at their mean).
      const double near = 2.0 * noise;
      std::size_t k = 0;
      for (std::size_t j = 0; j < outer.size(); ++j) {
        if (std::abs(outer[j] - end) <= near) kept[k++] = kept[j];
      }
      kept.resize(k);
      drop[s] = 1;
      ++stats.cylinders;
      const bool there =
          std::any_of(result.surfaces.begin(), result.surfaces.end(), [&](const Surface& other) {
            const auto* p = other.as<PlaneSurface>();
            return p != nullptr && p->normal.dot(m) > kParallel &&
                   std::abs(p->offset - offset) <= 2.0 * eps;
          });
      if (!there && kept.size() >= kMinEvidence / 2) {
        Surface face;
        face.shape = PlaneSurface{m, offset};
        face.rms = noise;
        face.inliers = std::move(kept);
        added.push_back(std::move(face));
      }
      break;
    }
    if (!drop[s] && round.as<CylinderSurface>() != nullptr &&
        inSheetCorner(cloud, result, round, sheets, options)) {
      drop[s] = 1;
      ++stats.corners;
    }
  }
  for (std::size_t s = 0; s < found; ++s) {
    if (!drop[s] && tiltedAtSheetEdge(cloud, result, s, sheets, noise)) {
      drop[s] = 1;
      ++stats.tilted;
    }
  }
  if (stats.tori + stats.cylinders + stats.corners + stats.tilted == 0) return stats;
  // Renumber: the kept surfaces in their order, then the end faces.
  const bool withCentroids = result.centroids.size() == found;
  std::vector<int> index(found, -1);
  std::vector<Surface> surfaces;
  std::vector<Vec3> centroids;
  for (std::size_t s = 0; s < found; ++s) {
    if (drop[s]) continue;
    index[s] = int(surfaces.size());
    surfaces.push_back(std::move(result.surfaces[s]));
    if (withCentroids) centroids.push_back(result.centroids[s]);
  }
  for (int& a : result.assignment) a = a >= 0 ? index[std::size_t(a)] : -1;
  for (Surface& face : added) {
    const int k = int(surfaces.size());
    Vec3 sum = Vec3::Zero();
    for (std::uint32_t i : face.inliers) {
      sum += cloud.points[i];
      result.assignment[i] = k;
    }
    if (withCentroids) centroids.push_back(sum / double(face.inliers.size()));
    surfaces.push_back(std::move(face));
  }
  result.surfaces = std::move(surfaces);
  if (withCentroids) result.centroids = std::move(centroids);
  return stats;
}

}  // namespace csgvox
