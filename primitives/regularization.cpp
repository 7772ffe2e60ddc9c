#include "primitives/regularization.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numeric>
#include <vector>

namespace csgvox {
namespace {

// The direction of a surface (plane normal, axis), or nullptr for spheres.
Vec3* directionOf(Surface& s) {
  if (auto* p = std::get_if<PlaneSurface>(&s.shape)) return &p->normal;
  if (auto* c = std::get_if<CylinderSurface>(&s.shape)) return &c->axisDir;
  if (auto* c = std::get_if<ConeSurface>(&s.shape)) return &c->axisDir;
  if (auto* t = std::get_if<TorusSurface>(&s.shape)) return &t->axisDir;
  return nullptr;
}

// A point on the axis of an axial surface (cylinder, cone, torus).
Vec3* axisPointOf(Surface& s) {
  if (auto* c = std::get_if<CylinderSurface>(&s.shape)) return &c->axisPoint;
  if (auto* c = std::get_if<ConeSurface>(&s.shape)) return &c->apex;
  if (auto* t = std::get_if<TorusSurface>(&s.shape)) return &t->center;
  return nullptr;
}

double weightOf(const Surface& s) { return double(std::max<std::size_t>(1, s.inliers.size())); }

double angleBetween(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Item indices by decreasing weight (ties in index order).
std::vector<std::size_t> heaviestFirst(const std::vector<double>& weights) {
  std::vector<std::size_t> order(weights.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return weights[a] > weights[b]; });
  return order;
}

// Greedy clustering of scalar or vector values, heaviest first: each cluster
// takes the unclustered items within `tolerance` of its seed. Returns the
// clusters as lists of item indices.
std::vector<std::vector<std::size_t>> clusterByWeight(
    const std::vector<double>& weights,
    const std::function<bool(std::size_t, std::size_t)>& close) {
  const std::vector<std::size_t> order = heaviestFirst(weights);
  std::vector<char> used(weights.size(), 0);
  std::vector<std::vector<std::size_t>> clusters;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t seed = order[k];
    if (used[seed]) continue;
    used[seed] = 1;
    std::vector<std::size_t> members{seed};
    for (std::size_t m = k + 1; m < order.size(); ++m) {
      const std::size_t j = order[m];
      if (!used[j] && close(seed, j)) {
        used[j] = 1;
        members.push_back(j);
      }
    }
    clusters.push_back(std::move(members));
  }
  return clusters;
}

// Greedy clustering of positions, heaviest first, measured from each
// cluster's weighted mean: the heaviest unclustered item seeds a cluster,
// which takes the unclustered compatible items within `tolerance` of its
// mean, recomputed until the members stop changing. A noisy surface that
// detection split into several fits has fits on both sides of its true
// position; measured from the heaviest fit alone, the far side is out of
// reach and stays a second surface.
std::vector<std::vector<std::size_t>> clusterAroundMean(
    const std::vector<double>& weights, const std::vector<Vec3>& positions, double tolerance,
    const std::function<bool(std::size_t, std::size_t)>& compatible) {
  constexpr int kMaxRounds = 16;
  const std::vector<std::size_t> order = heaviestFirst(weights);
  std::vector<char> used(weights.size(), 0);
  std::vector<std::vector<std::size_t>> clusters;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t seed = order[k];
    if (used[seed]) continue;
    used[seed] = 1;
    std::vector<std::size_t> members{seed};
    Vec3 centre = positions[seed];
    for (int round = 0; round < kMaxRounds; ++round) {
      std::vector<std::size_t> next{seed};
      Vec3 sum = weights[seed] * positions[seed];
      double w = weights[seed];
      for (std::size_t m = k + 1; m < order.size(); ++m) {
        const std::size_t j = order[m];
        if (used[j] || !compatible(seed, j) || (positions[j] - centre).norm() > tolerance) continue;
        next.push_back(j);
        sum += weights[j] * positions[j];
        w += weights[j];
      }
      const bool stable = next == members;
      members = std::move(next);
      centre = sum / w;
      if (stable) break;
    }
    for (std::size_t j : members) used[j] = 1;
    clusters.push_back(std::move(members));
  }
  return clusters;
}

// The field `Member` of a surface of type Shape; null for other types.
template <class Shape, double Shape::*Member>
double* fieldOf(Surface& s) {
  auto* shape = std::get_if<Shape>(&s.shape);
  return shape ? &(shape->*Member) : nullptr;
}

class Regularizer {
 public:
  Regularizer(DetectionResult& result, const RegularizeOptions& options)
      : r_(result), o_(options), alive_(result.surfaces.size(), 1) {
    const double eps = r_.epsilon > 0.0 ? r_.epsilon : 1e-3 * std::max(r_.diagonal, 1e-12);
    offsetTol_ = o_.offsetTolerance * eps;
    axisTol_ = o_.axisTolerance * eps;
    radiusTol_ = o_.radiusTolerance * eps;
    identical_ = 1e-9 * std::max(eps, 1e-300);
    for (std::size_t s = 0; s < r_.surfaces.size(); ++s) pivots_.push_back(pivotOf(s));
  }

  RegularizationReport run() {
    snapDirections();
    if (o_.mergeCoplanar) mergeCoplanar();
    if (o_.coaxial) snapCoaxial();
    if (o_.equalRadii) {
      snapEqualRadii();
      mergeIdentical();
    }
    compact();
    return report_;
  }

 private:
  Vec3 pivotOf(std::size_t s) {
    if (r_.centroids.size() == r_.surfaces.size() && !r_.surfaces[s].inliers.empty()) {
      return r_.centroids[s];
    }
    Surface& surf = r_.surfaces[s];
    if (const auto* p = surf.as<PlaneSurface>()) return p->offset * p->normal;
    if (const auto* sp = surf.as<SphereSurface>()) return sp->center;
    return *axisPointOf(surf);
  }

  // Turns surface s to the unit direction d (same sense as its current one),
  // pivoting about its centroid.
  void setDirection(std::size_t s, Vec3 d) {
    Surface& surf = r_.surfaces[s];
    Vec3& dir = *directionOf(surf);
    if (d.dot(dir) < 0.0) d = -d;
    const double rotation = angleBetween(dir, d);
    if (rotation == 0.0 && d == dir) return;
    report_.maxRotation = std::max(report_.maxRotation, rotation);
    const Vec3& c = pivots_[s];
    if (auto* p = std::get_if<PlaneSurface>(&surf.shape)) {
      p->normal = d;
      p->offset = d.dot(c);
    } else if (auto* cyl = std::get_if<CylinderSurface>(&surf.shape)) {
      cyl->axisPoint += (c - cyl->axisPoint).dot(cyl->axisDir) * cyl->axisDir;
      cyl->axisDir = d;
    } else if (auto* cone = std::get_if<ConeSurface>(&surf.shape)) {
      const Vec3 q = cone->apex + (c - cone->apex).dot(cone->axisDir) * cone->axisDir;
      const double t = (cone->apex - q).dot(cone->axisDir);
      cone->apex = q + t * d;
      cone->axisDir = d;
    } else if (auto* torus = std::get_if<TorusSurface>(&surf.shape)) {
      torus->axisDir = d;
    }
  }

  // Parallel classes of directions, then exact orthogonality between classes.
  void snapDirections() {
    std::vector<std::size_t> ids;
    std::vector<double> weights;
    for (std::size_t s = 0; s < r_.surfaces.size(); ++s) {
      if (directionOf(r_.surfaces[s])) {
        ids.push_back(s);
        weights.push_back(weightOf(r_.surfaces[s]));
      }
    }
    const double cosTol = std::cos(o_.angleTolerance), sinTol = std::sin(o_.angleTolerance);
    const auto dirOf = [&](std::size_t k) { return *directionOf(r_.surfaces[ids[k]]); };
    auto classes = clusterByWeight(weights, [&](std::size_t a, std::size_t b) {
      return std::abs(dirOf(a).dot(dirOf(b))) >= cosTol;
    });
    // Weighted mean direction of each class; heaviest class first.
    struct DirClass {
      std::vector<std::size_t> members;
      Vec3 dir;
      double weight = 0.0;
    };
    std::vector<DirClass> dirClasses;
    for (auto& members : classes) {
      DirClass c;
      const Vec3 seed = dirOf(members.front());
      Vec3 sum = Vec3::Zero();
      for (std::size_t k : members) {
        const Vec3 d = dirOf(k);
        sum += (d.dot(seed) < 0.0 ? -weights[k] : weights[k]) * d;
        c.weight += weights[k];
      }
      c.dir = sum.normalized();
      c.members = std::move(members);
      dirClasses.push_back(std::move(c));
    }
    std::stable_sort(dirClasses.begin(), dirClasses.end(),
                     [](const DirClass& a, const DirClass& b) { return a.weight > b.weight; });
    std::vector<Vec3> fixed;
    for (DirClass& c : dirClasses) {
      Vec3 d = c.dir;
      bool merged = false;
      for (const Vec3& f : fixed) {
        if (std::abs(d.dot(f)) >= cosTol) {
          d = d.dot(f) < 0.0 ? Vec3(-f) : f;
          merged = true;
          break;
        }
      }
      if (!merged && o_.orthogonal) {
        std::vector<Vec3> orth;
        for (const Vec3& f : fixed) {
          if (std::abs(d.dot(f)) <= sinTol) orth.push_back(f);
        }
        if (!orth.empty()) {
          const Vec3& f1 = orth.front();
          Vec3 d1 = (d - d.dot(f1) * f1).normalized();
          for (std::size_t k = 1; k < orth.size(); ++k) {
            if (std::abs(orth[k].dot(f1)) >= cosTol) continue;
            Vec3 cr = f1.cross(orth[k]).normalized();
            if (cr.dot(d1) < 0.0) cr = -cr;
            if (angleBetween(cr, d1) <= o_.angleTolerance) {
              d1 = cr;
              break;
            }
          }
          d = d1;
          ++report_.orthogonal;
        }
      }
      if (!merged) fixed.push_back(d);
      for (std::size_t k : c.members) {
        const Vec3 before = dirOf(k);
        setDirection(ids[k], d);
        if (c.members.size() > 1 && dirOf(k) != before) ++report_.parallel;
      }
    }
  }

  // Moves the inliers of `from` into `into` (both alive).
  void merge(std::size_t into, std::size_t from) {
    Surface& a = r_.surfaces[into];
    Surface& b = r_.surfaces[from];
    const double wa = double(a.inliers.size()), wb = double(b.inliers.size());
    if (wa + wb > 0.0) pivots_[into] = (wa * pivots_[into] + wb * pivots_[from]) / (wa + wb);
    a.inliers.insert(a.inliers.end(), b.inliers.begin(), b.inliers.end());
    std::sort(a.inliers.begin(), a.inliers.end());
    a.rms = std::sqrt((wa * a.rms * a.rms + wb * b.rms * b.rms) / std::max(1.0, wa + wb));
    b.inliers.clear();
    alive_[from] = 0;
  }

  void mergeCoplanar() {
    std::vector<std::size_t> planes;
    std::vector<double> weights;
    for (std::size_t s = 0; s < r_.surfaces.size(); ++s) {
      if (alive_[s] && r_.surfaces[s].type() == SurfaceType::Plane) {
        planes.push_back(s);
        weights.push_back(weightOf(r_.surfaces[s]));
      }
    }
    const auto plane = [&](std::size_t k) { return *r_.surfaces[planes[k]].as<PlaneSurface>(); };
    const auto clusters = clusterByWeight(weights, [&](std::size_t a, std::size_t b) {
      const PlaneSurface pa = plane(a), pb = plane(b);
      return pa.normal == pb.normal && std::abs(pa.offset - pb.offset) <= offsetTol_;
    });
    for (const auto& members : clusters) {
      if (members.size() < 2) continue;
      const std::size_t into = planes[members.front()];
      for (std::size_t m = 1; m < members.size(); ++m) {
        merge(into, planes[members[m]]);
        ++report_.coplanarMerged;
      }
      auto& p = std::get<PlaneSurface>(r_.surfaces[into].shape);
      const double offset = p.normal.dot(pivots_[into]);
      report_.maxShift = std::max(report_.maxShift, std::abs(offset - p.offset));
      p.offset = offset;
    }
  }

  // Appends the live surfaces for which `has` holds, and their weights.
  template <class Has>
  void liveSurfaces(Has has, std::vector<std::size_t>& ids, std::vector<double>& weights) {
    for (std::size_t s = 0; s < r_.surfaces.size(); ++s) {
      if (alive_[s] && has(r_.surfaces[s])) {
        ids.push_back(s);
        weights.push_back(weightOf(r_.surfaces[s]));
      }
    }
  }

  void snapCoaxial() {
    std::vector<std::size_t> axial;
    std::vector<double> weights;
    liveSurfaces([](Surface& s) { return axisPointOf(s) != nullptr; }, axial, weights);
    const auto dir = [&](std::size_t k) { return *directionOf(r_.surfaces[axial[k]]); };
    const auto foot = [&](std::size_t k) {  // where the axis meets the plane through 0 normal to it
      const Vec3 p = *axisPointOf(r_.surfaces[axial[k]]);
      const Vec3 d = dir(k);
      return Vec3(p - p.dot(d) * d);
    };
    std::vector<Vec3> feet;
    for (std::size_t k = 0; k < axial.size(); ++k) feet.push_back(foot(k));
    const auto clusters =
        clusterAroundMean(weights, feet, axisTol_, [&](std::size_t a, std::size_t b) {
          const Vec3 da = dir(a), db = dir(b);
          return da == db || da == -db;
        });
    std::vector<std::pair<Vec3, Vec3>> lines;  // (point, direction) of the shared axes
    for (const auto& members : clusters) {
      Vec3 sum = Vec3::Zero();
      double w = 0.0;
      for (std::size_t k : members) {
        sum += weights[k] * foot(k);
        w += weights[k];
      }
      const Vec3 shared = sum / w;
      const Vec3 d = dir(members.front());
      lines.emplace_back(shared, d);
      if (members.size() < 2) continue;
      for (std::size_t k : members) {
        const Vec3 shift = shared - foot(k);
        const Vec3 projected = shift - shift.dot(d) * d;  // stay exactly on the plane normal to d
        if (projected.norm() == 0.0) continue;
        *axisPointOf(r_.surfaces[axial[k]]) += projected;
        report_.maxShift = std::max(report_.maxShift, projected.norm());
        ++report_.coaxial;
      }
    }
    // Sphere centres close to a shared axis move onto it.
    for (std::size_t s = 0; s < r_.surfaces.size(); ++s) {
      if (!alive_[s]) continue;
      auto* sphere = std::get_if<SphereSurface>(&r_.surfaces[s].shape);
      if (!sphere) continue;
      double bestDistance = axisTol_;
      const std::pair<Vec3, Vec3>* best = nullptr;
      for (const auto& line : lines) {
        const Vec3 v = sphere->center - line.first;
        const double dist = (v - v.dot(line.second) * line.second).norm();
        if (dist <= bestDistance) {
          bestDistance = dist;
          best = &line;
        }
      }
      if (best && bestDistance > 0.0) {
        const Vec3 v = sphere->center - best->first;
        sphere->center = best->first + v.dot(best->second) * best->second;
        report_.maxShift = std::max(report_.maxShift, bestDistance);
        ++report_.coaxial;
      }
    }
  }

  // Clusters one scalar parameter of the surfaces selected by `get` (nullptr
  // to skip a surface) and sets each cluster to its weighted mean.
  void equalize(const std::function<double*(Surface&)>& get, double tolerance) {
    equalize(get, [tolerance](const Surface&, const Surface&) { return tolerance; });
  }

  // As above with a tolerance per pair of surfaces.
  void equalize(const std::function<double*(Surface&)>& get,
                const std::function<double(const Surface&, const Surface&)>& tolerance) {
    std::vector<std::size_t> ids;
    std::vector<double> weights;
    liveSurfaces([&](Surface& s) { return get(s) != nullptr; }, ids, weights);
    const auto value = [&](std::size_t k) { return *get(r_.surfaces[ids[k]]); };
    const auto clusters = clusterByWeight(weights, [&](std::size_t a, std::size_t b) {
      return std::abs(value(a) - value(b)) <= tolerance(r_.surfaces[ids[a]], r_.surfaces[ids[b]]);
    });
    for (const auto& members : clusters) {
      if (members.size() < 2) continue;
      double sum = 0.0, w = 0.0;
      for (std::size_t k : members) {
        sum += weights[k] * value(k);
        w += weights[k];
      }
      const double mean = sum / w;
      for (std::size_t k : members) {
        double& v = *get(r_.surfaces[ids[k]]);
        if (v != mean) {
          v = mean;
          ++report_.equalRadii;
        }
      }
    }
  }

  // Two fitted radii are the same design value when they differ by less
  // than their estimation error allows: the inlier band (epsilon) is far
  // wider than that and would merge a 5.5 hole with a 7.5 bore on a noisy
  // scan. A radius fitted to n points with noise sigma has a standard error
  // of about sigma / sqrt(n), doubled for partial arcs; radii within three
  // such errors (at least 0.1 % of D, at most the epsilon rule) are equal.
  double radiusTolerance(const Surface& a, const Surface& b) const {
    const auto se2 = [&](const Surface& s) {
      const double sigma = std::max(r_.noise, s.rms);
      return 4.0 * sigma * sigma / weightOf(s);
    };
    const double floor = 1e-3 * r_.diagonal;
    return std::min(radiusTol_, std::max(floor, 3.0 * std::sqrt(se2(a) + se2(b))));
  }

  void snapEqualRadii() {
    const auto tol = [this](const Surface& a, const Surface& b) { return radiusTolerance(a, b); };
    equalize(fieldOf<CylinderSurface, &CylinderSurface::radius>, tol);
    equalize(fieldOf<SphereSurface, &SphereSurface::radius>, tol);
    equalize(fieldOf<TorusSurface, &TorusSurface::majorRadius>, tol);
    equalize(fieldOf<TorusSurface, &TorusSurface::minorRadius>, tol);
    equalize(fieldOf<ConeSurface, &ConeSurface::halfAngle>, o_.angleTolerance);
  }

  // True when a and b are the same surface after snapping (b may be merged into a).
  bool identical(const Surface& a, const Surface& b) const {
    if (a.type() != b.type() || a.convex != b.convex) return false;
    const auto sameLine = [&](const Vec3& pa, const Vec3& da, const Vec3& pb, const Vec3& db) {
      if (!(da == db || da == -db)) return false;
      const Vec3 v = pb - pa;
      return (v - v.dot(da) * da).norm() <= axisTol_ * 1e-6 + identical_;
    };
    if (const auto* ca = a.as<CylinderSurface>()) {
      const auto* cb = b.as<CylinderSurface>();
      return ca->radius == cb->radius &&
             sameLine(ca->axisPoint, ca->axisDir, cb->axisPoint, cb->axisDir);
    }
    if (const auto* ca = a.as<ConeSurface>()) {
      const auto* cb = b.as<ConeSurface>();
      // Two cones of one angle on one axis are parallel surfaces
      // |apex shift| * sin(angle) apart: within the inlier band they are two
      // fits of one surface (RANSAC splits a noisy cone into the inner and
      // outer halves of its noise band).
      return ca->halfAngle == cb->halfAngle && ca->axisDir.dot(cb->axisDir) > 0.0 &&
             sameLine(ca->apex, ca->axisDir, cb->apex, cb->axisDir) &&
             (ca->apex - cb->apex).norm() * std::sin(ca->halfAngle) <= radiusTol_;
    }
    if (const auto* sa = a.as<SphereSurface>()) {
      const auto* sb = b.as<SphereSurface>();
      return sa->radius == sb->radius && (sa->center - sb->center).norm() <= radiusTol_;
    }
    if (const auto* ta = a.as<TorusSurface>()) {
      const auto* tb = b.as<TorusSurface>();
      return ta->majorRadius == tb->majorRadius && ta->minorRadius == tb->minorRadius &&
             sameLine(ta->center, ta->axisDir, tb->center, tb->axisDir) &&
             (ta->center - tb->center).norm() <= radiusTol_;
    }
    return false;
  }

  // Before two identical surfaces merge: the position that may still differ
  // (a cone's apex, a sphere's or torus' centre) becomes the inlier-weighted
  // mean of the two, as the parameters of merged planes and radii do.
  void meanPosition(std::size_t into, std::size_t from) {
    Surface& a = r_.surfaces[into];
    const Surface& b = r_.surfaces[from];
    const double wa = weightOf(a), wb = weightOf(b);
    const auto mean = [&](Vec3& pa, const Vec3& pb) { pa = (wa * pa + wb * pb) / (wa + wb); };
    if (auto* ca = std::get_if<ConeSurface>(&a.shape)) {
      mean(ca->apex, std::get<ConeSurface>(b.shape).apex);
    } else if (auto* sa = std::get_if<SphereSurface>(&a.shape)) {
      mean(sa->center, std::get<SphereSurface>(b.shape).center);
    } else if (auto* ta = std::get_if<TorusSurface>(&a.shape)) {
      mean(ta->center, std::get<TorusSurface>(b.shape).center);
    }
  }

  void mergeIdentical() {
    for (std::size_t a = 0; a < r_.surfaces.size(); ++a) {
      if (!alive_[a] || r_.surfaces[a].type() == SurfaceType::Plane) continue;
      for (std::size_t b = a + 1; b < r_.surfaces.size(); ++b) {
        if (!alive_[b] || !identical(r_.surfaces[a], r_.surfaces[b])) continue;
        const std::size_t into =
            r_.surfaces[a].inliers.size() >= r_.surfaces[b].inliers.size() ? a : b;
        meanPosition(into, into == a ? b : a);
        merge(into, into == a ? b : a);
        ++report_.duplicatesMerged;
        if (into == b) break;
      }
    }
  }

  // Drops merged surfaces, sorts by inlier count and renumbers the assignment.
  void compact() {
    std::vector<std::size_t> order;
    for (std::size_t s = 0; s < r_.surfaces.size(); ++s) {
      if (alive_[s]) order.push_back(s);
    }
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return r_.surfaces[a].inliers.size() > r_.surfaces[b].inliers.size();
    });
    std::vector<Surface> surfaces;
    std::vector<Vec3> centroids;
    for (std::size_t s : order) {
      surfaces.push_back(std::move(r_.surfaces[s]));
      centroids.push_back(pivots_[s]);
    }
    std::fill(r_.assignment.begin(), r_.assignment.end(), -1);
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      for (std::uint32_t i : surfaces[s].inliers) {
        if (i < r_.assignment.size()) r_.assignment[i] = int(s);
      }
    }
    r_.surfaces = std::move(surfaces);
    r_.centroids = std::move(centroids);
  }

  DetectionResult& r_;
  const RegularizeOptions& o_;
  RegularizationReport report_;
  std::vector<char> alive_;
  std::vector<Vec3> pivots_;
  double offsetTol_ = 0.0, axisTol_ = 0.0, radiusTol_ = 0.0, identical_ = 0.0;
};

}  // namespace

std::string RegularizationReport::summary() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "%d parallel, %d orthogonal, %d coplanar merged, %d coaxial, %d equal radii, "
                "%d duplicates merged (largest rotation %.3g deg, largest shift %.3g)",
                parallel, orthogonal, coplanarMerged, coaxial, equalRadii, duplicatesMerged,
                maxRotation * 180.0 / std::numbers::pi, maxShift);
  return buf;
}

RegularizationReport regularizeSurfaces(DetectionResult& result, const RegularizeOptions& options) {
  if (result.surfaces.empty()) return {};
  return Regularizer(result, options).run();
}

}  // namespace csgvox
