#include "primitives/surface_detection.h"

#include <CGAL/Random.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/property_map.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "core/nearest_neighbors.h"
#include "core/principal_axes.h"
#include "core/seed.h"
#include "core/statistics.h"
#include "primitives/cgal_kernel.h"
#include "primitives/even_subsample.h"
#include "primitives/surface_fit.h"

namespace csgvox {
namespace {

using cgal::Kernel;
using CPoint = cgal::Point3;
using CVector = cgal::Vector3;
// Efficient_RANSAC reorders its input, so each point carries its scan index.
using Pwn = std::tuple<CPoint, CVector, std::uint32_t>;
using PwnRange = std::vector<Pwn>;
using Traits =
    CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, PwnRange,
                                                   CGAL::Nth_of_tuple_property_map<0, Pwn>,
                                                   CGAL::Nth_of_tuple_property_map<1, Pwn>>;
using Ransac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;
using CgalPlane = CGAL::Shape_detection::Plane<Traits>;
using CgalCylinder = CGAL::Shape_detection::Cylinder<Traits>;
using CgalCone = CGAL::Shape_detection::Cone<Traits>;
using CgalSphere = CGAL::Shape_detection::Sphere<Traits>;
using CgalTorus = CGAL::Shape_detection::Torus<Traits>;

Vec3 toVec(const CPoint& p) { return {p.x(), p.y(), p.z()}; }

// A cone within this angle of flat or of a cylinder is refused (radians).
constexpr double kMinConeAngle = 2.0 * std::numbers::pi / 180.0;
Vec3 toVec(const CVector& v) { return {v.x(), v.y(), v.z()}; }

// Efficient_RANSAC draws from CGAL's thread-local default generator; this
// seeds it for one detection and restores it afterwards.
class ScopedCgalSeed {
 public:
  explicit ScopedCgalSeed(unsigned int seed) : saved_(CGAL::get_default_random()) {
    CGAL::get_default_random() = CGAL::Random(seed);
  }
  ~ScopedCgalSeed() { CGAL::get_default_random() = saved_; }
  ScopedCgalSeed(const ScopedCgalSeed&) = delete;
  ScopedCgalSeed& operator=(const ScopedCgalSeed&) = delete;

 private:
  CGAL::Random saved_;
};

unsigned int passSeed(std::uint64_t seed, int pass) {
  return static_cast<unsigned int>(mixSeed(seed, std::uint64_t(pass)) & 0x7fffffffu);
}

// The widest neighbourhood of estimateNoise, and the neighbours it gathers
// in all at most when it widens (counts).
constexpr std::size_t kNoiseMaxBall = 4096;
constexpr std::size_t kNoiseBudget = 4000 * 73;

// Indices 0, stride, 2*stride, ... covering at most `count` points.
std::vector<std::uint32_t> strideSubset(std::size_t n, std::size_t count) {
  const std::size_t stride = std::max<std::size_t>(1, n / std::max<std::size_t>(1, count));
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < n; i += stride) out.push_back(std::uint32_t(i));
  return out;
}

// Majority vote: true when most normals point along the outward direction
// returned by `outward(i)` for inlier i.
template <class Outward>
bool majorityOutward(const PointCloud& cloud, const std::vector<std::uint32_t>& inliers,
                     Outward outward) {
  std::size_t agree = 0;
  for (std::uint32_t i : inliers) agree += outward(cloud.points[i]).dot(cloud.normals[i]) > 0.0;
  return 2 * agree >= inliers.size();
}

// Whether a RANSAC shape's parameters can be one of our surfaces (as
// convertShape judges them): finite, a radius no larger than the diagonal, a
// cone neither within 2 degrees of flat nor of a cylinder, a torus' tube no
// wider than its ring.
bool plausibleParameters(const Ransac::Shape& shape, double diag) {
  const auto finite = [](const Vec3& v) { return v.allFinite(); };
  if (const auto* s = dynamic_cast<const CgalCylinder*>(&shape)) {
    const Vec3 dir = toVec(s->axis().to_vector());
    const double r = s->radius();
    return dir.norm() > 0.0 && finite(toVec(s->axis().point())) && finite(dir) && r > 0.0 &&
           r <= diag;
  }
  if (const auto* s = dynamic_cast<const CgalCone*>(&shape)) {
    const Vec3 dir = toVec(s->axis());
    const double angle = s->angle();
    return dir.norm() > 0.0 && finite(toVec(s->apex())) && finite(dir) &&
           angle >= kMinConeAngle && angle <= 0.5 * std::numbers::pi - kMinConeAngle;
  }
  if (const auto* s = dynamic_cast<const CgalSphere*>(&shape)) {
    const double r = s->radius();
    return finite(toVec(s->center())) && r > 0.0 && r <= diag;
  }
  if (const auto* s = dynamic_cast<const CgalTorus*>(&shape)) {
    const Vec3 dir = toVec(s->axis());
    const double major = s->major_radius(), minor = s->minor_radius();
    return dir.norm() > 0.0 && finite(toVec(s->center())) && finite(dir) && minor > 0.0 &&
           major >= minor && major <= diag;
  }
  return true;  // a plane
}

// The diagonal against which RANSAC's candidates are judged in this thread
// (infinite: every candidate is scored).
thread_local double tCandidateDiagonal = std::numeric_limits<double>::infinity();

// A RANSAC shape scored only when its parameters are plausible. On normals
// estimated from raw points, nearly parallel normals make cones, tori and
// cylinders wide enough to touch both faces of a thin plate, or two walls,
// at once; RANSAC extracted them for their many points, convertShape refused
// them, and the walls' points were lost to the pass (a raw thin plate with
// small holes: 4 planes found for 26 faces).
template <class Base>
class PlausibleShape : public Base {
 protected:
  void create_shape(const std::vector<std::size_t>& indices) override {
    Base::create_shape(indices);
    if (this->m_is_valid && !plausibleParameters(*this, tCandidateDiagonal)) {
      this->m_is_valid = false;
    }
  }
};

// Converts a CGAL shape into a Surface on the scan's points; returns false for
// shapes that are not plausible features of a part of diagonal D.
bool convertShape(const Ransac::Shape& shape, const PointCloud& cloud, double diag, Surface& out) {
  const auto finite = [](const Vec3& v) { return v.allFinite(); };
  if (const auto* s = dynamic_cast<const CgalPlane*>(&shape)) {
    Vec3 n = toVec(s->plane_normal());
    const double len = n.norm();
    if (!(len > 0.0) || !finite(n)) return false;
    n /= len;
    double offset = -s->d() / len;
    if (!majorityOutward(cloud, out.inliers, [&](const Vec3&) { return n; })) {
      n = -n;
      offset = -offset;
    }
    out.shape = PlaneSurface{n, offset};
    out.convex = true;
    return std::isfinite(offset);
  }
  if (const auto* s = dynamic_cast<const CgalCylinder*>(&shape)) {
    const Vec3 point = toVec(s->axis().point());
    Vec3 dir = toVec(s->axis().to_vector());
    const double r = s->radius();
    if (!(dir.norm() > 0.0) || !finite(point) || !finite(dir) || !(r > 0.0) || !(r <= diag)) {
      return false;
    }
    dir.normalize();
    CylinderSurface c{point, dir, r};
    out.convex = majorityOutward(cloud, out.inliers, [&](const Vec3& p) {
      const Vec3 d = p - c.axisPoint;
      return Vec3(d - d.dot(c.axisDir) * c.axisDir);
    });
    out.shape = c;
    return true;
  }
  if (const auto* s = dynamic_cast<const CgalCone*>(&shape)) {
    const Vec3 apex = toVec(s->apex());
    Vec3 dir = toVec(s->axis());
    const double angle = s->angle();
    if (!(dir.norm() > 0.0) || !finite(apex) || !finite(dir) || !(angle >= kMinConeAngle) ||
        !(angle <= 0.5 * std::numbers::pi - kMinConeAngle)) {
      return false;
    }
    dir.normalize();
    ConeSurface c{apex, dir, angle};
    // The inliers must lie on the nappe the axis points into.
    std::size_t ahead = 0;
    for (std::uint32_t i : out.inliers) ahead += (cloud.points[i] - apex).dot(dir) > 0.0;
    if (2 * ahead < out.inliers.size()) return false;
    // Outward normal of the cone surface (away from the axis, tilted back to the apex).
    out.convex = majorityOutward(cloud, out.inliers, [&](const Vec3& p) {
      const Vec3 d = p - c.apex;
      Vec3 radial = d - d.dot(c.axisDir) * c.axisDir;
      const double rn = radial.norm();
      if (rn > 0.0) radial /= rn;
      return Vec3(std::cos(c.halfAngle) * radial - std::sin(c.halfAngle) * c.axisDir);
    });
    out.shape = c;
    return true;
  }
  if (const auto* s = dynamic_cast<const CgalSphere*>(&shape)) {
    const Vec3 centre = toVec(s->center());
    const double r = s->radius();
    if (!finite(centre) || !(r > 0.0) || !(r <= diag)) return false;
    out.convex =
        majorityOutward(cloud, out.inliers, [&](const Vec3& p) { return Vec3(p - centre); });
    out.shape = SphereSurface{centre, r};
    return true;
  }
  if (const auto* s = dynamic_cast<const CgalTorus*>(&shape)) {
    const Vec3 centre = toVec(s->center());
    Vec3 dir = toVec(s->axis());
    const double major = s->major_radius(), minor = s->minor_radius();
    if (!(dir.norm() > 0.0) || !finite(centre) || !finite(dir) || !(minor > 0.0) ||
        !(major >= minor) || !(major <= diag)) {
      return false;
    }
    dir.normalize();
    TorusSurface t{centre, dir, major, minor};
    out.convex = majorityOutward(cloud, out.inliers, [&](const Vec3& p) {
      const Vec3 d = p - t.center;
      Vec3 radial = d - d.dot(t.axisDir) * t.axisDir;
      const double rn = radial.norm();
      if (rn > 0.0) radial /= rn;
      return Vec3(p - (t.center + t.majorRadius * radial));  // from the tube's centre circle
    });
    out.shape = t;
    return true;
  }
  return false;
}

// Why the points cannot be the scan of a solid, or an empty string.
std::string degeneracy(const PointCloud& cloud, double diag) {
  if (cloud.size() < 3) {
    return "only " + std::to_string(cloud.size()) + " point(s): at least 3 are needed";
  }
  if (!(diag > 0.0)) return "all points are identical";
  const Vec3 sd = principalAxes(cloud.points).variances.cwiseMax(0.0).cwiseSqrt();  // descending
  char buf[160];
  if (sd[1] < 1e-6 * diag) {
    std::snprintf(buf, sizeof(buf),
                  "all points lie on one line (spread across it %.2g %% of the diagonal)",
                  100.0 * sd[1] / diag);
    return buf;
  }
  if (sd[2] < 1e-4 * diag) {
    std::snprintf(buf, sizeof(buf),
                  "all points lie in one plane (thickness %.2g %% of the diagonal): not the "
                  "scan of a solid",
                  100.0 * sd[2] / diag);
    return buf;
  }
  return {};
}

void validate(const PointCloud& cloud, const DetectOptions& o) {
  if (cloud.size() >= 3 && !cloud.hasNormals()) {
    throw std::invalid_argument("detectSurfaces needs one normal per point (estimate them first)");
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.points[i].allFinite() || !cloud.normals[i].allFinite()) {
      throw std::invalid_argument("point " + std::to_string(i) +
                                  " has a non-finite coordinate or normal");
    }
  }
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(o.epsilon) || !positive(o.clusterEpsilon) || !(o.noiseFactor >= 0.0) ||
      !(o.spacingFactor >= 0.0) || !positive(o.maxEpsilon) || !(o.normalThreshold >= 0.0) ||
      !(o.normalThreshold <= 1.0) || !(o.minPoints >= 0.0) || !(o.minPoints < 1.0) ||
      !(o.probability > 0.0) || !(o.probability < 1.0) || o.passes < 1 ||
      !(o.laterPassMinPoints > 0.0) || !(o.laterPassMinPoints <= 1.0) ||
      (o.ransacPoints > 0 && o.ransacPoints < 100)) {
    throw std::invalid_argument("detectSurfaces: an option is out of range");
  }
}

// One RANSAC pass over the points `subset`; appends the accepted surfaces
// (inliers as scan indices), in detection order, after `accept` (model
// selection) kept them. Each shape is final once RANSAC extracts it, so it is
// converted and selected in a TBB task while RANSAC searches on; every task
// writes its own slot, so the result does not depend on the scheduling.
// With `judgeCandidates` (normals estimated from raw points), RANSAC scores
// only candidates whose parameters are plausible (PlausibleShape).
// Returns false when cancelled.
bool ransacPass(const PointCloud& cloud, const std::vector<std::uint32_t>& subset,
                const std::set<SurfaceType>& types, const Ransac::Parameters& params,
                unsigned int seed, double diag, bool judgeCandidates,
                const std::function<bool(double)>& callback,
                const std::function<bool(Surface&)>& accept, std::vector<Surface>& found) {
  if (subset.size() < params.min_points || subset.size() < 10) return true;
  struct ScopedDiagonal {
    double saved;
    ~ScopedDiagonal() { tCandidateDiagonal = saved; }
  } scopedDiagonal{std::exchange(
      tCandidateDiagonal,
      judgeCandidates ? diag : std::numeric_limits<double>::infinity())};
  PwnRange input;
  input.reserve(subset.size());
  for (std::uint32_t i : subset) {
    const Vec3& p = cloud.points[i];
    const Vec3& n = cloud.normals[i];
    input.emplace_back(CPoint(p.x(), p.y(), p.z()), CVector(n.x(), n.y(), n.z()), i);
  }
  ScopedCgalSeed seeded(seed);
  Ransac ransac;
  ransac.set_input(input);
  if (types.count(SurfaceType::Plane)) ransac.add_shape_factory<CgalPlane>();
  if (types.count(SurfaceType::Cylinder)) ransac.add_shape_factory<PlausibleShape<CgalCylinder>>();
  if (types.count(SurfaceType::Cone)) ransac.add_shape_factory<PlausibleShape<CgalCone>>();
  if (types.count(SurfaceType::Sphere)) ransac.add_shape_factory<PlausibleShape<CgalSphere>>();
  if (types.count(SurfaceType::Torus)) ransac.add_shape_factory<PlausibleShape<CgalTorus>>();
  ransac.preprocess();
  // Scan index of each (reordered) input point; preprocess() was the last reordering.
  std::vector<std::uint32_t> scanIndex(input.size());
  for (std::size_t k = 0; k < input.size(); ++k) scanIndex[k] = std::get<2>(input[k]);

  // One slot per extracted shape; deque: slots stay put while tasks write them.
  std::deque<std::optional<Surface>> slots;
  tbb::task_group tasks;
  const auto launch = [&]() {
    const auto shapes = ransac.shapes();
    std::size_t k = 0;
    for (auto it = shapes.begin(); it != shapes.end(); ++it, ++k) {
      if (k < slots.size()) continue;
      std::optional<Surface>& slot = slots.emplace_back();
      tasks.run([&, shape = *it, &slot = slot]() {
        Surface s;
        for (std::size_t local : shape->indices_of_assigned_points())
          s.inliers.push_back(scanIndex[local]);
        std::sort(s.inliers.begin(), s.inliers.end());
        if (s.inliers.size() < params.min_points) return;
        if (!convertShape(*shape, cloud, diag, s) || !accept(s)) return;
        slot = std::move(s);
      });
    }
  };
  bool cancelled = false;
  try {
    ransac.detect(params, [&](double f) {
      launch();
      if (callback && !callback(f)) cancelled = true;
      return !cancelled;
    });
  } catch (...) {
    tasks.cancel();
    tasks.wait();
    throw;
  }
  if (cancelled) {
    tasks.cancel();
    tasks.wait();
    return false;
  }
  launch();
  tasks.wait();
  for (std::optional<Surface>& slot : slots) {
    if (slot) found.push_back(std::move(*slot));
  }
  return true;
}

// Where a raw scan's second selection cost stops growing, in noise units (see
// selectModel): past the Gaussian bulk. (With that cost alone deciding, 2.5
// sigma gave the same count of InverseCSG scanner scans at IoU 0.95 as 3,
// with larger swings per part.)
constexpr double kRawSelectionSigmas = 3.0;

// Robust costs of a surface on points, in units of the noise. `full`: per
// point the fit's scaled squared distance (capped at `cap`) plus its scaled
// squared normal deviation (capped at kNormalChi2), both caps for points
// whose normal disagrees. `bulk` (only when asked): the distances alone,
// capped at `bulkCap`, and that cap for points whose normal disagrees.
struct SelectionCosts {
  double full = 0.0;
  double bulk = 0.0;
};

SelectionCosts selectionCosts(const PointCloud& cloud, const std::vector<std::uint32_t>& indices,
                              const Surface& s, const FitScales& scales, double cap,
                              double bulkCap, bool withBulk, double threshold) {
  SelectionCosts c;
  for (std::uint32_t i : indices) {
    const PointFit fit = pointFit(s, cloud.points[i], cloud.normals[i], scales);
    if (fit.cosine < threshold) {
      c.full += cap + kNormalChi2;
      if (withBulk) c.bulk += bulkCap;
      continue;
    }
    const double d2 = std::pow(fit.distance / scales.position, 2);
    c.full += std::min(cap, d2) + std::min(kNormalChi2, fit.normal2);
    if (withBulk) c.bulk += std::min(bulkCap, d2);
  }
  return c;
}

// Normal noise measured on detected surfaces whose normals do not vary: for
// each plane with at least 50 inliers, the median angle between an inlier's
// normal and the plane's (Rayleigh: median = 1.1774 sigma); else, for each
// such cylinder, the median axial component of its inliers' normals
// (half-normal: median = 0.6745 sigma). The smallest per-surface value wins,
// so a spurious surface with scattered normals does not inflate it.
// Negative when no surface qualifies. Unlike estimateNormalNoise it is not
// fooled by estimated normals that are smooth between neighbours yet off the
// true surface.
double normalNoiseOnSurfaces(const PointCloud& cloud, const std::vector<Surface>& surfaces) {
  double planar = -1.0, axial = -1.0;
  for (const Surface& s : surfaces) {
    if (s.inliers.size() < 50) continue;
    std::vector<double> v;
    if (const auto* pl = s.as<PlaneSurface>()) {
      for (std::uint32_t i : s.inliers) {
        v.push_back(std::atan2(pl->normal.cross(cloud.normals[i]).norm(),
                               std::abs(pl->normal.dot(cloud.normals[i]))));
      }
      const double est = median(std::move(v)) / 1.1774;
      planar = planar < 0.0 ? est : std::min(planar, est);
    } else if (const auto* c = s.as<CylinderSurface>()) {
      for (std::uint32_t i : s.inliers) v.push_back(std::abs(c->axisDir.dot(cloud.normals[i])));
      const double est = median(std::move(v)) / 0.6745;
      axial = axial < 0.0 ? est : std::min(axial, est);
    }
  }
  return planar >= 0.0 ? planar : axial;
}

// Model selection for one RANSAC shape: the shape refined, and every enabled
// type started in closed form on its inliers and fitted; the lowest robust
// cost plus a BIC penalty (parameters x ln n) wins. RANSAC readily explains a
// narrow plane strip by a large cylinder, a spherical zone by a cylinder or a
// chamfer band by a sphere; this undoes that. Returns false when no plausible
// surface remains.
bool selectModel(const PointCloud& cloud, const DetectOptions& o, const FitScales& scales,
                 double eps, double diag, bool raw, Surface& shape) {
  SurfaceFitOptions fit;
  fit.maxFitPoints = 600;  // enough to tell the types apart
  fit.maxIterations = 25;
  std::vector<Surface> candidates;
  Surface refined = shape;
  if (fitSurface(cloud, shape.inliers, refined, scales, fit) >= 0.0 &&
      plausibleSurface(refined, diag, cloud, shape.inliers)) {
    candidates.push_back(refined);
  } else if (plausibleSurface(shape, diag, cloud, shape.inliers)) {
    candidates.push_back(shape);
  }
  // A plane whose inliers' normals all agree with it is a plane: no curved
  // surface can explain it better (this saves most of the fits).
  if (!candidates.empty() && candidates.front().type() == SurfaceType::Plane) {
    const Vec3 n = candidates.front().as<PlaneSurface>()->normal;
    const double cosTol = std::cos(std::max(3.0 * scales.normal, 0.02));
    std::size_t flat = 0;
    for (std::uint32_t i : shape.inliers) flat += n.dot(cloud.normals[i]) >= cosTol;
    if (double(flat) >= 0.95 * double(shape.inliers.size())) {
      std::vector<std::uint32_t> inliers = std::move(shape.inliers);
      shape = std::move(candidates.front());
      shape.inliers = std::move(inliers);
      return true;
    }
  }
  for (SurfaceType t : o.enabled) {
    Surface alt;
    if (!initialSurface(cloud, shape.inliers, t, alt) ||
        !plausibleSurface(alt, diag, cloud, shape.inliers)) {
      continue;
    }
    if (fitSurface(cloud, shape.inliers, alt, scales, fit) < 0.0 ||
        !plausibleSurface(alt, diag, cloud, shape.inliers)) {
      continue;
    }
    candidates.push_back(std::move(alt));
  }
  if (candidates.empty()) return false;
  const double logN = std::log(double(std::max<std::size_t>(2, shape.inliers.size())));
  const double cap = std::pow(eps / scales.position, 2);
  const double bulkCap = std::min(cap, kRawSelectionSigmas * kRawSelectionSigmas);
  // A raw scan's points between a few sigma and eps are mostly edges' mixed
  // pixels and blended corners, and its normals there are smeared; they can
  // outweigh the bulk, so that a bent cone, a sphere or a small cylinder that
  // follows them beats the plane the bulk lies on. The positions alone,
  // truncated at a few sigma, judge the bulk: where they prefer a simpler
  // type, it is taken. (Where they prefer a more complex one, the two costs
  // disagree and the data do not support it either: a concave corner's
  // blended points fit a small cylinder closer than either face.)
  std::size_t chosen = 0, bulk = 0;
  double bestFull = std::numeric_limits<double>::infinity(), bestBulk = bestFull;
  for (std::size_t j = 0; j < candidates.size(); ++j) {
    const double penalty = parameterCount(candidates[j].type()) * logN;
    const SelectionCosts c = selectionCosts(cloud, shape.inliers, candidates[j], scales, cap,
                                            bulkCap, raw, o.normalThreshold);
    if (c.full + penalty < bestFull) {
      bestFull = c.full + penalty;
      chosen = j;
    }
    if (raw && c.bulk + penalty < bestBulk) {
      bestBulk = c.bulk + penalty;
      bulk = j;
    }
  }
  if (raw && parameterCount(candidates[bulk].type()) < parameterCount(candidates[chosen].type())) {
    chosen = bulk;
  }
  std::vector<std::uint32_t> inliers = std::move(shape.inliers);
  shape = std::move(candidates[chosen]);
  shape.inliers = std::move(inliers);
  return true;
}

}  // namespace

std::string_view detectionStatusName(DetectionResult::Status status) {
  switch (status) {
    case DetectionResult::Status::Ok:
      return "ok";
    case DetectionResult::Status::NoSurfaces:
      return "no surfaces";
    case DetectionResult::Status::DegenerateInput:
      return "degenerate input";
    case DetectionResult::Status::Cancelled:
      return "cancelled";
  }
  return "unknown";
}

namespace {

// The estimators below on a prebuilt neighbour structure of the cloud's points.
double estimateNoise(const PointCloud& cloud, const NearestNeighbors& nn, int neighbors) {
  const std::size_t k = std::size_t(std::max(neighbors, 8));
  if (cloud.size() < k + 1) return 0.0;
  const bool normals = cloud.hasNormals();
  // Each sampled point's k nearest neighbours *in its tangent plane*: a plane
  // fitted to its k nearest in space would be flattened by the noise (the
  // ball of a noisy point holds the points on its side of the surface, and
  // where the ball is not much wider than the noise the fit's least spread
  // runs along the surface), and wider balls reach edges and thin walls.
  // The normal comes from the `wide` nearest that face the same way (normals
  // within about 45 degrees, so the faces across an edge or a thin wall stay
  // out); the heights of the k+1 along it are fitted by a quadric over the
  // tangent plane (6 coefficients: tilt and curvature absorbed, so a clean
  // curved face reads 0), and the residual is sigma^2 chi^2(k-5)/(k+1).
  // The k+1 are taken from the `wide` nearest in space, which must hold the
  // whole noise band over their disc: where the points are dense against
  // the noise, 6k+1 in space lie within a sigma or two of the point's own
  // height, and the disc's heights, cut to that band, read low (half of
  // sigma at 300 000 points and 1 % noise). So the ball widens until it
  // reaches 3 sigma above and below the disc's rim; wider balls are
  // measured on fewer points (kNoiseBudget neighbours in all, at least 250
  // points), which the median still tells within a few per cent.
  std::size_t wide = std::min(cloud.size(), 6 * k + 1);
  // The median of chi^2(nu) (Wilson-Hilferty), nu = k + 1 - 6.
  const double m = double(k + 1), nu = m - 6.0;
  const double chiMedian = nu * std::pow(1.0 - 2.0 / (9.0 * nu), 3.0);
  while (true) {
    const std::vector<std::uint32_t> sample =
        strideSubset(cloud.size(), std::clamp<std::size_t>(kNoiseBudget / wide, 250, 4000));
    std::vector<double> rms(sample.size(), -1.0), ball(sample.size(), -1.0),
        disc(sample.size(), -1.0);
    tbb::parallel_for(std::size_t(0), sample.size(), [&](std::size_t s) {
      std::vector<std::uint32_t> idx, same;
      std::vector<double> d2;
      std::vector<std::pair<double, Vec3>> near;  // (tangent distance^2, offset)
      const std::uint32_t i = sample[s];
      const Vec3& p = cloud.points[i];
      nn.kNearest(p, wide, idx, &d2);
      for (std::uint32_t j : idx) {
        if (!normals || cloud.normals[j].dot(cloud.normals[i]) > 0.7) same.push_back(j);
      }
      if (same.size() < k + 1) return;
      const PrincipalAxes axes = principalAxes(cloud.points, same);
      const Vec3 n = axes.axes.col(2), u = axes.axes.col(0), v = axes.axes.col(1);
      near.reserve(same.size());
      for (std::uint32_t j : same) {
        const Vec3 d = cloud.points[j] - p;
        near.emplace_back(d.squaredNorm() - d.dot(n) * d.dot(n), d);
      }
      std::nth_element(near.begin(), near.begin() + std::ptrdiff_t(k), near.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      Eigen::MatrixXd a(k + 1, 6);
      Eigen::VectorXd h(k + 1);
      for (std::size_t t = 0; t <= k; ++t) {
        const Vec3& d = near[t].second;
        const double x = d.dot(u), y = d.dot(v);
        a.row(Eigen::Index(t)) << 1.0, x, y, x * x, x * y, y * y;
        h(Eigen::Index(t)) = d.dot(n);
      }
      const Eigen::VectorXd c = a.colPivHouseholderQr().solve(h);
      rms[s] = std::sqrt((a * c - h).squaredNorm() / double(k + 1));
      ball[s] = std::sqrt(d2.back());
      disc[s] = std::sqrt(std::max(0.0, near[k].first));
    });
    std::erase_if(rms, [](double r) { return r < 0.0; });
    if (rms.empty()) return 0.0;
    std::erase_if(ball, [](double r) { return r < 0.0; });
    std::erase_if(disc, [](double r) { return r < 0.0; });
    const double sigma = median(std::move(rms)) * std::sqrt(m / chiMedian);
    if (wide >= std::min(cloud.size(), kNoiseMaxBall) ||
        median(std::move(ball)) >= std::hypot(median(std::move(disc)), 3.0 * sigma)) {
      return sigma;
    }
    wide = std::min({2 * wide, cloud.size(), kNoiseMaxBall});
  }
}

double estimateNormalNoise(const PointCloud& cloud, const NearestNeighbors& nn) {
  if (cloud.size() < 2 || !cloud.hasNormals()) return 0.0;
  const std::vector<std::uint32_t> sample = strideSubset(cloud.size(), 4000);
  std::vector<double> angle(sample.size());
  tbb::parallel_for(std::size_t(0), sample.size(), [&](std::size_t s) {
    std::vector<std::uint32_t> idx;
    nn.kNearest(cloud.points[sample[s]], 2, idx);
    const Vec3& a = cloud.normals[sample[s]];
    const Vec3& b = cloud.normals[idx.back()];
    angle[s] = std::atan2(a.cross(b).norm(), a.dot(b));
  });
  return median(std::move(angle)) / std::numbers::sqrt2;
}

double estimateSpacing(const PointCloud& cloud, const NearestNeighbors& nn) {
  if (cloud.size() < 2) return 0.0;
  const std::vector<std::uint32_t> sample = strideSubset(cloud.size(), 4000);
  std::vector<double> dist(sample.size());
  tbb::parallel_for(std::size_t(0), sample.size(), [&](std::size_t s) {
    std::vector<std::uint32_t> idx;
    std::vector<double> d2;
    nn.kNearest(cloud.points[sample[s]], 2, idx, &d2);
    dist[s] = d2.size() == 2 ? std::sqrt(d2[1]) : 0.0;
  });
  return median(std::move(dist));
}

// Scale-free parameters: relative to D (result.diagonal), raised to what the
// noise and the sampling density require.
// A non-negative `noise` is the noise sigma measured beforehand.
void setScales(const PointCloud& cloud, const DetectOptions& options, double noise,
               DetectionResult& result) {
  const double diag = result.diagonal;
  const NearestNeighbors nn(cloud.points);
  result.noise = noise >= 0.0 ? noise : estimateNoise(cloud, nn, kNoiseNeighbors);
  result.normalNoise = estimateNormalNoise(cloud, nn);
  const double spacing = estimateSpacing(cloud, nn);
  result.epsilon = std::max(options.epsilon * diag, std::min(options.noiseFactor * result.noise,
                                                             options.maxEpsilon * diag));
  result.clusterEpsilon = std::max(options.clusterEpsilon * diag, options.spacingFactor * spacing);
  result.minPoints = std::max<std::size_t>(
      options.minPointsFloor, std::size_t(std::lround(options.minPoints * double(cloud.size()))));
}

// One RANSAC pass: the surface types it looks for and its minimum support.
struct Stage {
  std::set<SurfaceType> types;
  std::size_t minPoints;
};

// RANSAC stages. Staged: planes and cylinders first, then cones and spheres,
// then tori, so that a flexible surface cannot claim the points of several
// simpler ones (a torus over a hole and its countersink). Then later passes
// with all types and fewer points for small features.
std::vector<Stage> ransacStages(const DetectOptions& options, std::size_t minPoints) {
  std::vector<Stage> stages;
  if (options.staged) {
    std::set<SurfaceType> sofar;
    for (const auto& group : {std::set<SurfaceType>{SurfaceType::Plane, SurfaceType::Cylinder},
                              std::set<SurfaceType>{SurfaceType::Cone, SurfaceType::Sphere},
                              std::set<SurfaceType>{SurfaceType::Torus}}) {
      bool added = false;
      for (SurfaceType t : group) {
        if (options.enabled.count(t) && sofar.insert(t).second) added = true;
      }
      if (added) stages.push_back({sofar, minPoints});
    }
  } else {
    stages.push_back({options.enabled, minPoints});
  }
  for (int pass = 1; pass < options.passes; ++pass) {
    minPoints = std::max<std::size_t>(
        std::min<std::size_t>(options.minPointsFloor, minPoints),
        std::size_t(std::lround(double(minPoints) * options.laterPassMinPoints)));
    stages.push_back({options.enabled, minPoints});
  }
  return stages;
}

// Settles the surfaces found so far: drops redundant ones, gives every point
// to the surface that explains it best, re-fits. `subset` becomes the
// unassigned points, which later stages search. On a raw scan the points
// left over once the surfaces are settled go to them by distance and the
// cosine threshold alone (reassignPoints without the normal noise test):
// within a few neighbourhoods of an edge a normal blends the two faces
// beyond the noise measured inside them, and held to that noise those bands
// (a fifth of the points of a thin-walled part) were left to the later
// stages, which searched them for small spurious cylinders, cones and tori.
// (The final assignment, detectAndFit's fit, holds the normals to the noise
// again: the stages after detection read a surface's inliers as its seen
// extent.)
void settle(const PointCloud& cloud, DetectionResult& result, std::vector<Surface>& found,
            std::vector<std::uint32_t>& subset, FitMemo& memo, bool raw) {
  result.surfaces = std::move(found);
  result.status = DetectionResult::Status::Ok;
  SurfaceFitOptions settle;
  settle.maxFitPoints = 3000;
  // Points a surface's band reaches away from its patch stay with it until
  // the final refinement: the later passes search the unassigned points
  // for new surfaces, and stray noise is no help there.
  settle.connectedPatches = false;
  // The passes keep the surfaces as RANSAC found them; the final refinement
  // turns the flattened ones into planes and splits stepped cylinders.
  settle.flattenToPlanes = false;
  settle.splitSteps = false;
  settle.normalNoiseTest = !raw;
  fitSurfaces(cloud, result, settle, &memo);
  found = std::move(result.surfaces);
  result.surfaces.clear();
  subset.clear();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (result.assignment[i] < 0) subset.push_back(std::uint32_t(i));
  }
}

// Leaves out of the later stages' search the unassigned points that a
// surface already found beside them explains by distance. Two kinds of
// points are left over by the stages although they lie on surfaces found:
// - near sharp edges, normals estimated from raw points blend the two faces
//   and fail the normal test of both (about a tenth of a raw scan of a
//   bracket), and the later stages explain those strips by small spurious
//   cylinders, cones and planes (a false rounded edge);
// - a scanner's depth noise grows with range and at grazing incidence, so
//   where a surface's inliers spread wide, its noise reaches past epsilon.
// A point goes when at least two of its k nearest neighbours are inliers of
// one surface and it lies within epsilon + 3 x their RMS distance from it
// (epsilon alone on a clean scan). Its assignment does not change: the
// final refinement decides it by distance and normal as before.
// A leftover point whose normal is farther than this (cosine) from a
// surface beside it lies on a face that crosses it (about 65 degrees: a
// sharpened edge normal lies within 26 of its face, a blended one halfway).
constexpr double kCrossingCosine = 0.42;

void dropExplainedLeftovers(const PointCloud& cloud, const NearestNeighbors& nn,
                            const std::vector<Surface>& found, const std::vector<int>& assignment,
                            double epsilon, std::vector<std::uint32_t>& subset) {
  constexpr std::size_t k = 12;
  constexpr double tails = 3.0;
  if (found.empty() || cloud.size() <= k) return;
  std::vector<char> drop(subset.size(), 0);
  tbb::parallel_for(std::size_t{0}, subset.size(), [&](std::size_t j) {
    const Vec3& p = cloud.points[subset[j]];
    thread_local std::vector<std::uint32_t> near;
    thread_local std::vector<int> seen;
    nn.kNearest(p, k + 1, near);
    seen.clear();
    for (const std::uint32_t q : near) {
      const int s = assignment[q];
      if (s < 0 || std::find(seen.begin(), seen.end(), s) != seen.end()) continue;
      seen.push_back(s);
      const Surface& surface = found[std::size_t(s)];
      double sum = 0.0;
      std::size_t votes = 0;
      for (const std::uint32_t r : near) {
        if (assignment[r] != s) continue;
        const double d = surfaceDistance(surface, cloud.points[r]);
        sum += d * d;
        ++votes;
      }
      if (votes < 2) continue;
      const double rms = std::sqrt(sum / double(votes));
      // A point whose normal crosses the surface lies on a face of its own
      // that meets this one (the wall of a hole in a plate thinner than a
      // few epsilon), not on a strip of blended normals beside it.
      if (std::abs(surfaceNormal(surface, p).dot(cloud.normals[subset[j]])) < kCrossingCosine) {
        continue;
      }
      if (surfaceDistance(surface, p) <= epsilon + tails * rms) {
        drop[j] = 1;
        return;
      }
    }
  });
  std::size_t kept = 0;
  for (std::size_t j = 0; j < subset.size(); ++j) {
    if (!drop[j]) subset[kept++] = subset[j];
  }
  subset.resize(kept);
}

// The final status and message of a detection.
void summarise(const PointCloud& cloud, DetectionResult& result) {
  const double diag = result.diagonal;
  std::size_t assigned = 0;
  std::array<int, 5> perType{};
  for (const Surface& surf : result.surfaces) {
    assigned += surf.inliers.size();
    ++perType[std::size_t(surf.type())];
  }
  char buf[320];
  if (result.surfaces.empty()) {
    result.status = DetectionResult::Status::NoSurfaces;
    std::snprintf(buf, sizeof(buf),
                  "no surface explains %zu or more points within %.3g (%.2g %% of the diagonal; "
                  "estimated noise %.3g)",
                  result.minPoints, result.epsilon, 100.0 * result.epsilon / diag, result.noise);
  } else {
    result.status = DetectionResult::Status::Ok;
    std::snprintf(buf, sizeof(buf),
                  "%zu surfaces (%d planes, %d cylinders, %d cones, %d spheres, %d tori) explain "
                  "%.1f %% of the points; epsilon %.3g (%.2g %% of D), estimated noise %.3g",
                  result.surfaces.size(), perType[0], perType[1], perType[2], perType[3],
                  perType[4], 100.0 * double(assigned) / double(cloud.size()), result.epsilon,
                  100.0 * result.epsilon / diag, result.noise);
  }
  result.message = buf;
}

}  // namespace

double estimateNoise(const PointCloud& cloud, int neighbors) {
  if (cloud.size() < std::size_t(std::max(neighbors, 4)) + 1) return 0.0;
  return estimateNoise(cloud, NearestNeighbors(cloud.points), neighbors);
}

double estimateNormalNoise(const PointCloud& cloud) {
  if (cloud.size() < 2 || !cloud.hasNormals()) return 0.0;
  return estimateNormalNoise(cloud, NearestNeighbors(cloud.points));
}

double estimateSpacing(const PointCloud& cloud) {
  if (cloud.size() < 2) return 0.0;
  return estimateSpacing(cloud, NearestNeighbors(cloud.points));
}

namespace {

// detectSurfaces on all the points of a validated cloud; a non-negative
// `noise` is its noise sigma, measured beforehand.
DetectionResult detectOnAll(const PointCloud& cloud, const DetectOptions& options,
                            const ProgressCallback& progress, double noise = -1.0) {
  using Status = DetectionResult::Status;
  DetectionResult result;
  result.assignment.assign(cloud.size(), -1);
  result.normalThreshold = options.normalThreshold;
  const double diag = cloud.empty() ? 0.0 : cloud.diagonal();
  result.diagonal = diag;
  const auto report = [&](double f, std::string_view stage) {
    return !progress || progress(std::clamp(f, 0.0, 1.0), stage);
  };
  const auto cancelled = [&]() {
    result.status = Status::Cancelled;
    result.message = "surface detection was cancelled";
    return result;
  };

  if (std::string why = degeneracy(cloud, diag); !why.empty()) {
    result.status = Status::DegenerateInput;
    result.message = "cannot detect surfaces: " + why;
    return result;
  }
  if (!report(0.0, "noise")) return cancelled();

  setScales(cloud, options, noise, result);

  if (options.enabled.empty()) {
    result.status = Status::NoSurfaces;
    result.message = "no surface types are enabled";
    return result;
  }

  const std::vector<Stage> stages = ransacStages(options, result.minPoints);
  FitScales scales = fitScales(result);
  // Normals estimated from raw points, or (decided on the first stage's
  // surfaces) a scanner's.
  bool raw = options.estimatedNormals;
  std::optional<NearestNeighbors> nn;
  if (raw) nn.emplace(cloud.points);
  std::vector<Surface> found;
  // The stages settle the surfaces found so far again after each pass, most
  // of them unchanged: their fits are looked up.
  FitMemo fits(cloud);
  std::vector<std::uint32_t> subset(cloud.size());
  for (std::size_t i = 0; i < subset.size(); ++i) subset[i] = std::uint32_t(i);
  for (std::size_t stage = 0; stage < stages.size(); ++stage) {
    Ransac::Parameters params;
    params.probability = options.probability;
    params.min_points = stages[stage].minPoints;
    params.epsilon = result.epsilon;
    params.cluster_epsilon = result.clusterEpsilon;
    params.normal_threshold = options.normalThreshold;
    const double span = 0.9 / double(stages.size()), base = 0.05 + span * double(stage);
    const std::function<bool(double)> cb = [&](double f) {
      return report(base + span * f, "ransac");
    };
    const std::function<bool(Surface&)> accept = [&](Surface& surf) {
      return selectModel(cloud, options, scales, result.epsilon, diag, raw, surf);
    };
    if (!ransacPass(cloud, subset, stages[stage].types, params, passSeed(options.seed, int(stage)),
                    diag, raw, cb, accept, found)) {
      return cancelled();
    }
    if (stage == 0) {
      // Measure the normal noise on the first surfaces, and use it from now on.
      if (const double sn = normalNoiseOnSurfaces(cloud, found); sn >= 0.0) {
        result.normalNoise = sn;
        scales = fitScales(result);
      }
      if (!raw && result.normalNoise > options.scannerNormalNoise) {
        raw = true;
        nn.emplace(cloud.points);
      }
    }
    result.minPoints = std::min(result.minPoints, stages[stage].minPoints);
    settle(cloud, result, found, subset, fits, raw);
    if (raw) {
      dropExplainedLeftovers(cloud, *nn, found, result.assignment, result.epsilon, subset);
    }
  }
  if (!report(0.95, "ransac")) return cancelled();

  result.surfaces = std::move(found);
  result.searchedPoints = cloud.size();
  result.rawNormals = raw;
  summarise(cloud, result);
  report(1.0, "ransac");
  return result;
}

// The seed of the subsample, apart from those of the RANSAC passes.
constexpr std::uint64_t kSubsampleStream = 1000;

// detectSurfaces on an even subsample of a large cloud, then every point
// assigned. The noise is estimated on a stride subset of the subsample's
// size (the estimate does not depend on the density, and a stride keeps the
// noise's distribution as it is); it sizes the subsample's cells and is the
// detection's noise.
DetectionResult detectOnSubsample(const PointCloud& cloud, const DetectOptions& options,
                                  const ProgressCallback& progress) {
  const double diag = cloud.diagonal();
  if (std::string why = degeneracy(cloud, diag); !why.empty()) {
    DetectionResult result;
    result.assignment.assign(cloud.size(), -1);
    result.diagonal = diag;
    result.normalThreshold = options.normalThreshold;
    result.status = DetectionResult::Status::DegenerateInput;
    result.message = "cannot detect surfaces: " + why;
    return result;
  }
  PointCloud stride;
  for (std::uint32_t i : strideSubset(cloud.size(), options.ransacPoints)) {
    stride.points.push_back(cloud.points[i]);
    stride.normals.push_back(cloud.normals[i]);
  }
  const double noise = estimateNoise(stride, kNoiseNeighbors);
  stride = {};
  SubsampleOptions so;
  so.points = options.ransacPoints;
  so.seed = mixSeed(options.seed, kSubsampleStream);
  const std::vector<std::uint32_t> chosen = evenSubsample(cloud.points, noise, so);
  const PointCloud sub = cloud.subset(chosen);
  const auto scaled = [&](double f, std::string_view stage) {
    return !progress || progress(0.95 * f, stage);
  };
  DetectionResult result = detectOnAll(sub, options, scaled, noise);
  // The decisions that depend on the density are taken on the subsample.
  if (result.ok()) fitSurfaces(sub, result);
  result.searchedPoints = sub.size();
  result.searched = chosen;
  result.diagonal = diag;
  result.assignment.assign(cloud.size(), -1);
  for (Surface& s : result.surfaces) s.inliers.clear();
  if (!result.ok()) return result;
  // The least support, the same fraction of all points as of the subsample's.
  result.minPoints = std::max<std::size_t>(
      options.minPointsFloor,
      std::size_t(std::llround(double(result.minPoints) * double(cloud.size()) /
                               double(sub.size()))));
  reassignPoints(cloud, result, result.minPoints, true);
  summarise(cloud, result);
  result.message += "; searched on " + std::to_string(sub.size()) + " of the " +
                    std::to_string(cloud.size()) + " points";
  if (progress && !progress(1.0, "ransac")) {
    result.status = DetectionResult::Status::Cancelled;
    result.message = "surface detection was cancelled";
  }
  return result;
}

}  // namespace

DetectionResult detectSurfaces(const PointCloud& cloud, const DetectOptions& options,
                               const ProgressCallback& progress) {
  validate(cloud, options);
  if (options.ransacPoints > 0 && cloud.size() > options.ransacPoints) {
    return detectOnSubsample(cloud, options, progress);
  }
  return detectOnAll(cloud, options, progress);
}

}  // namespace csgvox
