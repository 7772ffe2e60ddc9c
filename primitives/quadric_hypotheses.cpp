// Quadric hypotheses (Wu et al. 2018 §3.2 and §4.1, Fayolle & Pasko 2016
// §5.2): bounded cylinders, cone frustums, spheres and tori from their
// patches; the additional box of each patch (minimal oriented bounding box,
// or the maximal box of a quarter cylinder); the indirect candidates
// box − quadric and box ∩ quadric; the separators.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include "primitives/hypotheses_internal.h"

namespace csgvox::hypotheses_detail {
namespace {

constexpr double kPi = std::numbers::pi;

// The box with axes `frame` around the points, with robust extents.
Box boxAround(const Mat3& frame, std::span<const Vec3> points, double sigma) {
  std::array<Range, 3> r;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> t;
    t.reserve(points.size());
    for (const Vec3& p : points) t.push_back(p.dot(frame.col(k)));
    r[static_cast<std::size_t>(k)] = robustRange(std::move(t), sigma);
  }
  return boxFromRanges(frame, r);
}

// The point of the surface nearest to p (the inliers projected onto their
// fitted surface bound the patch without the noise across it).
Vec3 projectOnto(const SurfaceShape& shape, const Vec3& p) {
  auto radialOf = [](const Vec3& d, const Vec3& axis) {
    const Vec3 r = d - d.dot(axis) * axis;
    const double n = r.norm();
    return n > 0.0 ? Vec3(r / n) : frameFromAxis(axis).col(0);
  };
  if (const auto* c = std::get_if<CylinderSurface>(&shape)) {
    const Vec3 a = c->axisDir.normalized(), d = p - c->axisPoint;
    return c->axisPoint + d.dot(a) * a + c->radius * radialOf(d, a);
  }
  if (const auto* c = std::get_if<ConeSurface>(&shape)) {
    const Vec3 a = c->axisDir.normalized(), d = p - c->apex;
    const Vec3 g = std::cos(c->halfAngle) * a + std::sin(c->halfAngle) * radialOf(d, a);
    return c->apex + std::max(0.0, d.dot(g)) * g;
  }
  if (const auto* c = std::get_if<SphereSurface>(&shape)) {
    const Vec3 d = p - c->center;
    return c->center + c->radius * (d.norm() > 0.0 ? Vec3(d.normalized()) : Vec3::UnitZ());
  }
  if (const auto* c = std::get_if<TorusSurface>(&shape)) {
    const Vec3 a = c->axisDir.normalized();
    const Vec3 tube = c->center + c->majorRadius * radialOf(p - c->center, a);
    const Vec3 d = p - tube;
    return tube + c->minorRadius * (d.norm() > 0.0 ? Vec3(d.normalized()) : a);
  }
  return p;
}

// Positions of `points` along the line through `origin` with unit direction `axis`.
std::vector<double> axialPositions(std::span<const Vec3> points, const Vec3& origin,
                                   const Vec3& axis) {
  std::vector<double> t;
  t.reserve(points.size());
  for (const Vec3& p : points) t.push_back((p - origin).dot(axis));
  return t;
}

// A fitted quadric with its bounded primitive.
struct Quadric {
  std::size_t surface = 0;
  Primitive primitive;
  std::vector<Vec3> points;  // inliers projected onto the surface
  double sigma = 0.0;
  bool axial = false;             // cylinder, cone, torus: has an axis
  Vec3 axis = Vec3::UnitZ();      // unit
  Vec3 axisPoint = Vec3::Zero();  // origin of the axial coordinate t
  Range extent;                   // of the inliers along the axis (t)
  Range dense;  // a cylinder's extent without sparse ends (denseRange), else `extent`
  std::array<bool, 2> capped{false, false};  // lower, upper end on a fitted plane
};

// The bounded primitive of a surface from its inliers; nullopt when the
// parameters are degenerate.
std::optional<Quadric> boundedQuadric(const Context& ctx, std::size_t index) {
  const Surface& s = ctx.surfaces[index];
  Quadric q;
  q.surface = index;
  q.points = inlierPoints(ctx.scan, s);
  for (Vec3& p : q.points) p = projectOnto(s.shape, p);
  q.sigma = s.rms;  // what is left: noise along the surface
  const double minSize = 1e-6 * ctx.diagonal;
  // The inliers' extent along the axis; `dense` also drops sparse ends (cylinders).
  auto axialRange = [&](const Vec3& origin, const Vec3& axis, bool dense = false) {
    const std::vector<double> t = axialPositions(q.points, origin, axis);
    q.axial = true;
    q.axis = axis;
    q.axisPoint = origin;
    q.extent = robustRange(t, q.sigma);
    q.dense = dense ? denseRange(t, q.extent) : q.extent;
  };
  if (const auto* c = s.as<CylinderSurface>()) {
    if (!(c->radius > 0.0) || !(c->axisDir.norm() > 0.0)) return std::nullopt;
    axialRange(c->axisPoint, c->axisDir.normalized(), true);
    if (!(q.extent.size() > minSize)) return std::nullopt;
    q.primitive = Cylinder{q.axisPoint + 0.5 * (q.extent.lo + q.extent.hi) * q.axis, q.axis,
                           c->radius, q.extent.size()};
  } else if (const auto* c = s.as<ConeSurface>()) {
    if (!(c->halfAngle > 0.0 && c->halfAngle < 0.5 * kPi) || !(c->axisDir.norm() > 0.0)) {
      return std::nullopt;
    }
    axialRange(c->apex, c->axisDir.normalized());
    q.extent.lo = std::max(q.extent.lo, 0.0);
    if (!(q.extent.size() > minSize)) return std::nullopt;
    const double tanA = std::tan(c->halfAngle);
    q.primitive = Cone{q.axisPoint + 0.5 * (q.extent.lo + q.extent.hi) * q.axis, q.axis,
                       q.extent.lo * tanA, q.extent.hi * tanA, q.extent.size()};
  } else if (const auto* c = s.as<SphereSurface>()) {
    if (!(c->radius > 0.0)) return std::nullopt;
    q.primitive = Sphere{c->center, c->radius};
  } else if (const auto* c = s.as<TorusSurface>()) {
    if (!(c->minorRadius > 0.0 && c->minorRadius <= c->majorRadius) || !(c->axisDir.norm() > 0.0)) {
      return std::nullopt;
    }
    axialRange(c->center, c->axisDir.normalized());
    q.primitive = Torus{c->center, q.axis, c->majorRadius, c->minorRadius};
  } else {
    return std::nullopt;
  }
  return q;
}

// True when box a is the bounding box of the bounded quadric itself (then it
// adds nothing: Wu drops it).
bool isOwnBoundingBox(const Box& a, const Primitive& q, double tol, double cosTol) {
  Vec3 center, axis = Vec3::Zero();
  double along = 0.0, across = 0.0;  // half extents along and across the axis
  if (const auto* c = q.as<Cylinder>()) {
    center = c->center, axis = c->axis, along = 0.5 * c->height, across = c->radius;
  } else if (const auto* c = q.as<Cone>()) {
    center = c->center, axis = c->axis, along = 0.5 * c->height;
    across = std::max(c->radiusBottom, c->radiusTop);
  } else if (const auto* c = q.as<Torus>()) {
    center = c->center, axis = c->axis, along = c->minorRadius;
    across = c->majorRadius + c->minorRadius;
  } else if (const auto* c = q.as<Sphere>()) {
    center = c->center, along = across = c->radius;
  } else {
    return false;
  }
  if ((a.center - center).norm() > tol) return false;
  int alongAxis = -1;
  if (axis.squaredNorm() > 0.0) {
    for (int k = 0; k < 3; ++k) {
      if (std::abs(a.axes.col(k).dot(axis)) >= cosTol) alongAxis = k;
    }
    if (alongAxis < 0) return false;
  }
  for (int k = 0; k < 3; ++k) {
    const double expected = k == alongAxis || alongAxis < 0 ? along : across;
    if (std::abs(a.halfSize[k] - expected) > tol) return false;
  }
  return true;
}

// Angular span of the points around the cylinder axis: start angle and
// coverage (2 pi minus the largest gap), in the frame frameFromAxis(axis).
void angularSpan(const Quadric& q, double& start, double& coverage) {
  const Mat3 f = frameFromAxis(q.axis);
  std::vector<double> a;
  a.reserve(q.points.size());
  for (const Vec3& p : q.points) {
    const Vec3 d = p - q.axisPoint;
    a.push_back(std::atan2(d.dot(f.col(1)), d.dot(f.col(0))));
  }
  std::sort(a.begin(), a.end());
  double gap = a.front() + 2.0 * kPi - a.back();
  start = a.front();
  for (std::size_t i = 1; i < a.size(); ++i) {
    if (a[i] - a[i - 1] > gap) {
      gap = a[i] - a[i - 1];
      start = a[i];
    }
  }
  coverage = 2.0 * kPi - gap;
}

// Plane surfaces as seen by the cap extension and the separator filter.
struct PlaneInfo {
  std::size_t surface = 0;
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  Vec3 centroid = Vec3::Zero();
  std::vector<Vec3> sample;  // up to 512 inliers, evenly spread
};

// Wu Fig. 6(2): the maximal box of a quarter cylinder, a square of side r
// with a corner on the axis, spanning the quarter. Its sides lie along the
// normals of the planes the quarter meets tangentially (a rounded edge). The
// points' span is not exact there: the inliers run a little onto the planes,
// where plane and cylinder agree within the noise, which turns the box by up
// to half the excess and leaves slivers along both edges. So when a fitted
// plane parallel to the axis lies at the radius from it with its normal
// within the quarter tolerance of a side, the box turns onto that normal
// (the nearest such plane decides).
Box quarterBox(const Context& ctx, const Quadric& q, double radius, double start, double coverage,
               const std::vector<PlaneInfo>& planes) {
  const Mat3 f = frameFromAxis(q.axis);
  double mid = start + 0.5 * coverage;
  auto dir = [&](double ang) { return Vec3(std::cos(ang) * f.col(0) + std::sin(ang) * f.col(1)); };
  double within = ctx.options.quarterTolerance * kPi / 180.0, turn = 0.0;
  for (const PlaneInfo& pl : planes) {
    if (std::abs(pl.normal.dot(q.axis)) > ctx.sinOrthogonal) continue;  // not along the axis
    if (std::abs(std::abs(pl.normal.dot(q.axisPoint) - pl.offset) - radius) >
        ctx.lengthTol + 2.0 * q.sigma) {
      continue;
    }
    const double a = std::atan2(pl.normal.dot(f.col(1)), pl.normal.dot(f.col(0)));
    for (double side : {mid - 0.25 * kPi, mid + 0.25 * kPi}) {
      // The normal's angle from the side, modulo a half turn (its sign is free).
      const double d = std::remainder(a - side, kPi);
      if (std::abs(d) < within) within = std::abs(d), turn = d;
    }
  }
  mid += turn;
  Mat3 frame;
  frame.col(0) = dir(mid - 0.25 * kPi);
  frame.col(1) = dir(mid + 0.25 * kPi);
  frame.col(2) = q.axis;  // e0 x e1 = axis: right-handed
  const Vec3 origin = q.axisPoint;
  const double o0 = origin.dot(frame.col(0)), o1 = origin.dot(frame.col(1)),
               o2 = origin.dot(frame.col(2));
  return boxFromRanges(frame, {Range{o0, o0 + radius}, Range{o1, o1 + radius},
                               Range{o2 + q.extent.lo, o2 + q.extent.hi}});
}

// The minimal box of an axial patch with one axis on the quadric's axis: the
// minimum-area rectangle of the points projected along the axis.
Box axialMinimalBox(const Quadric& q) {
  const Mat3 f = frameFromAxis(q.axis);
  std::vector<Eigen::Vector2d> uv;
  uv.reserve(q.points.size());
  for (const Vec3& p : q.points) uv.emplace_back(p.dot(f.col(0)), p.dot(f.col(1)));
  const Rectangle2 rect = minAreaRectangle(uv);
  Mat3 frame;
  frame.col(0) = rect.direction.x() * f.col(0) + rect.direction.y() * f.col(1);
  frame.col(2) = q.axis;
  frame.col(1) = q.axis.cross(frame.col(0));
  return boxAround(frame, q.points, q.sigma);
}

std::vector<PlaneInfo> planeInfos(const Context& ctx) {
  std::vector<PlaneInfo> planes;
  for (const PlaneRef& ref : planeSurfaces(ctx)) {
    const Surface& surface = *ref.surface;
    const PlaneSurface* pl = ref.plane;
    PlaneInfo info;
    info.surface = ref.index;
    info.normal = pl->normal.normalized();
    info.offset = pl->offset / pl->normal.norm();
    for (std::uint32_t i : surface.inliers) info.centroid += ctx.scan.points[i];
    info.centroid /= static_cast<double>(surface.inliers.size());
    const std::size_t step = std::max<std::size_t>(1, surface.inliers.size() / 512);
    for (std::size_t i = 0; i < surface.inliers.size(); i += step) {
      info.sample.push_back(ctx.scan.points[surface.inliers[i]]);
    }
    planes.push_back(std::move(info));
  }
  return planes;
}

// True when a cone or torus patch coaxial with the cylinder spans [t0, t1]
// along its axis (within a voxel): the chamfer or round between its end and
// a cap.
bool bridged(const Context& ctx, const Quadric& cyl, double t0, double t1,
             const std::vector<std::optional<Quadric>>& quadrics) {
  return std::any_of(quadrics.begin(), quadrics.end(), [&](const std::optional<Quadric>& q) {
    if (!q || !q->axial || q->primitive.type() == PrimitiveType::Cylinder) return false;
    if (std::abs(q->axis.dot(cyl.axis)) < ctx.cosParallel) return false;
    const Vec3 d = q->axisPoint - cyl.axisPoint;
    if ((d - d.dot(cyl.axis) * cyl.axis).norm() > ctx.lengthTol) return false;  // not coaxial
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& p : q->points) {
      const double t = (p - cyl.axisPoint).dot(cyl.axis);
      lo = std::min(lo, t), hi = std::max(hi, t);
    }
    return lo <= t0 + ctx.voxel && hi >= t1 - ctx.voxel;
  });
}

// The plane patch that caps the cylinder past one end of its inliers, behind
// a chamfer or round (the end face of a chamfered shaft or boss):
// perpendicular to the axis, at most one radius past the end, with most of
// its points inside the cylinder, and a coaxial cone or torus patch spanning
// the gap. Returns the plane's axial position and surface, nearest first.
std::optional<std::pair<double, std::size_t>> capPlane(
    const Context& ctx, const Quadric& q, double radius, bool upper,
    const std::vector<PlaneInfo>& planes, const std::vector<std::optional<Quadric>>& quadrics) {
  std::optional<std::pair<double, std::size_t>> best;
  const double end = upper ? q.extent.hi : q.extent.lo;
  for (const PlaneInfo& pl : planes) {
    if (std::abs(pl.normal.dot(q.axis)) < ctx.cosParallel) continue;
    const double t = (pl.centroid - q.axisPoint).dot(q.axis);
    const double gap = upper ? t - end : end - t;
    if (!(gap > ctx.lengthTol && gap <= radius)) continue;
    if (best && std::abs(t - end) >= std::abs(best->first - end)) continue;
    std::size_t inside = 0;
    for (const Vec3& p : pl.sample) {
      const Vec3 d = p - q.axisPoint;
      inside += (d - d.dot(q.axis) * q.axis).norm() <= radius + 0.5 * ctx.voxel;
    }
    if (2 * inside < pl.sample.size()) continue;
    if (!bridged(ctx, q, std::min(t, end), std::max(t, end), quadrics)) continue;
    best = std::make_pair(t, pl.surface);
  }
  return best;
}

// Moves the ends of a bounded cylinder or cone frustum onto the fitted planes
// that cap or cross it there: perpendicular to the axis, within the end's
// uncertainty (three noise deviations, at least twice the duplicate
// tolerance) and touching the rim there. A plane is fitted to thousands of
// points, so its position is far more accurate than the extreme inliers of a
// noisy patch; without this, a noisy disk comes out a fraction of a voxel too
// tall and the optimisation pays a box to trim it.
void snapEndsToPlanes(const Context& ctx, Quadric& q, const std::vector<PlaneInfo>& planes) {
  const auto* cyl = q.primitive.as<Cylinder>();
  const auto* cone = q.primitive.as<Cone>();
  if (cyl == nullptr && cone == nullptr) return;
  // Radius at axial position t (t from q.axisPoint: the cone's apex).
  const double slope =
      cone != nullptr ? (cone->radiusTop - cone->radiusBottom) / cone->height : 0.0;
  const auto radiusAt = [&](double t) { return cyl != nullptr ? cyl->radius : t * slope; };
  const double tol = std::max(3.0 * q.sigma, 2.0 * ctx.lengthTol);
  Range extent = q.extent;
  // A sparse end (the noise tail of a neighbouring surface) is dropped only
  // where the dense patch ends on a plane; without one the end stays where
  // the inliers end (a cylinder meeting another one obliquely thins out
  // towards its end and is no shorter for it).
  const auto nearestPlane = [&](double end) {
    double best = std::numeric_limits<double>::infinity();
    for (const PlaneInfo& pl : planes) {
      const double cosine = pl.normal.dot(q.axis);
      if (std::abs(cosine) < ctx.cosParallel) continue;
      const double t = (pl.offset - pl.normal.dot(q.axisPoint)) / cosine;
      if (!(std::abs(t - end) <= tol) || std::abs(t - end) >= std::abs(best - end)) continue;
      if (cone != nullptr && !(t >= 0.0)) continue;  // past the apex
      int rim = 0;
      for (const Vec3& p : pl.sample) {
        const Vec3 d = p - q.axisPoint;
        rim += std::abs((d - d.dot(q.axis) * q.axis).norm() - radiusAt(t)) <= ctx.voxel;
      }
      if (rim >= 3) best = t;
    }
    return best;
  };
  for (const bool upper : {false, true}) {
    const double denseEnd = upper ? q.dense.hi : q.dense.lo;
    const double end = upper ? q.extent.hi : q.extent.lo;
    double best =
        denseEnd != end ? nearestPlane(denseEnd) : std::numeric_limits<double>::infinity();
    if (!std::isfinite(best)) best = nearestPlane(end);
    if (std::isfinite(best)) {
      (upper ? extent.hi : extent.lo) = best;
      q.capped[upper ? 1 : 0] = true;
    }
  }
  if (!(extent.size() > 0.5 * q.extent.size())) {
    q.capped = {false, false};
    return;
  }
  q.extent = extent;
  const Vec3 center = q.axisPoint + 0.5 * (extent.lo + extent.hi) * q.axis;
  if (cyl != nullptr) {
    q.primitive = Cylinder{center, q.axis, cyl->radius, extent.size()};
  } else {
    q.primitive = Cone{center, q.axis, radiusAt(extent.lo), radiusAt(extent.hi), extent.size()};
  }
}

// The bands of a convex cylinder or cone patch that empty gaps across its
// whole circumference separate: a groove cut into a boss, a neck between two
// shoulders of the same radius, the rounded ends of two parallel plates on
// one axis; one surface to the detection. Bounded by all its inliers, the
// quadric fills the gap with material that is not there. Each band is the
// patch's quadric bounded by its own inliers, its ends snapped onto the
// fitted planes there (the groove's walls). A gap counts when it is wider
// than twice the duplicate tolerance, than the span that holds ten inliers at
// the patch's mean density along the axis (the sampling leaves no such gap
// by chance) and than six deviations of the patch's noise (each band's edge
// spreads three into the gap, and the band ends there are no better known).
// Only the dense part of the patch is split (a sparse tail is no band).
// Empty when the patch is one band, or more than kMaxBands (ribs or threads:
// the whole patch stands for them), and for a hole: a hole through two
// walls, subtracted whole, mostly cuts the air between them, and splitting
// holes lowered as many InverseCSG parts as it raised.
// A band: its bounded primitive and how many inliers it holds.
struct Band {
  Primitive primitive;
  std::size_t inliers = 0;
};

std::vector<Band> axialBands(const Context& ctx, const Quadric& q,
                             const std::vector<PlaneInfo>& planes) {
  constexpr std::size_t kMaxBands = 4;
  if (q.primitive.as<Cylinder>() == nullptr && q.primitive.as<Cone>() == nullptr) return {};
  if (!ctx.surfaces[q.surface].convex || !(q.dense.size() > 0.0)) return {};
  std::vector<double> t = axialPositions(q.points, q.axisPoint, q.axis);
  std::erase_if(t, [&](double v) { return v < q.dense.lo || v > q.dense.hi; });
  if (t.size() < 2 * kMinInliers) return {};
  std::sort(t.begin(), t.end());
  const double minGap = std::max(
      {2.0 * ctx.lengthTol, 10.0 * q.dense.size() / static_cast<double>(t.size()), 6.0 * q.sigma});
  std::vector<std::size_t> starts{0};  // first index of each band in t
  for (std::size_t k = 1; k < t.size(); ++k) {
    if (t[k] - t[k - 1] > minGap) starts.push_back(k);
  }
  if (starts.size() < 2 || starts.size() > kMaxBands) return {};
  starts.push_back(t.size());
  std::vector<Band> out;
  for (std::size_t b = 0; b + 1 < starts.size(); ++b) {
    const std::size_t first = starts[b], last = starts[b + 1] - 1;
    if (last + 1 - first < kMinInliers) continue;
    // The quadric over the band alone (snapEndsToPlanes reads no points).
    // The patch's own (snapped) ends stay; the gap's edges are the inliers'.
    Quadric band;
    band.primitive = q.primitive;
    band.sigma = q.sigma;
    band.axis = q.axis;
    band.axisPoint = q.axisPoint;
    band.extent = {b == 0 ? q.extent.lo : t[first], last + 1 == t.size() ? q.extent.hi : t[last]};
    if (!(band.extent.size() > 1e-6 * ctx.diagonal)) continue;
    band.dense = band.extent;
    snapEndsToPlanes(ctx, band, planes);  // with no plane there, sets the band's own ends
    out.push_back({band.primitive, last + 1 - first});
  }
  return out;
}

// True when the plane n·x = offset is (within tolerance) one of the fitted planes.
bool isFittedPlane(const Context& ctx, const Vec3& n, const Vec3& onPlane,
                   const std::vector<PlaneInfo>& planes) {
  return std::any_of(planes.begin(), planes.end(), [&](const PlaneInfo& pl) {
    return std::abs(pl.normal.dot(n)) >= ctx.cosParallel &&
           std::abs(pl.normal.dot(onPlane) - pl.offset) <= ctx.lengthTol;
  });
}

Candidate makeCandidate(CsgTree tree, CandidateOrigin origin, std::vector<int> surfaces,
                        double support) {
  Candidate c;
  c.tree = std::move(tree);
  c.origin = origin;
  std::sort(surfaces.begin(), surfaces.end());
  c.surfaces = std::move(surfaces);
  c.support = support;
  return c;
}

// Each surface's bounded quadric (none for planes and for surfaces that
// give none), its ends snapped onto `planes` when the options ask.
std::vector<std::optional<Quadric>> boundedQuadrics(const Context& ctx,
                                                    const std::vector<PlaneInfo>& planes,
                                                    HypothesisStats& stats) {
  std::vector<std::optional<Quadric>> quadrics(ctx.surfaces.size());
  for (std::size_t s = 0; s < ctx.surfaces.size(); ++s) {
    const Surface& surface = ctx.surfaces[s];
    if (surface.type() == SurfaceType::Plane) {
      stats.skippedSurfaces += surface.inliers.size() < kMinInliers ? 1 : 0;
      continue;
    }
    if (surface.inliers.size() >= kMinInliers) quadrics[s] = boundedQuadric(ctx, s);
    if (!quadrics[s]) ++stats.skippedSurfaces;
    if (quadrics[s] && ctx.options.snapToPlanes) snapEndsToPlanes(ctx, *quadrics[s], planes);
  }
  return quadrics;
}

// The candidates made from each bounded quadric: what they are made from
// (the fitted planes, those ends and quarter boxes snap onto, every
// surface's bounded quadric) and where they go.
struct QuadricCandidates {
  const Context& ctx;
  HypothesisStats& stats;
  const std::vector<PlaneInfo>& planes;
  const std::vector<PlaneInfo>& snapPlanes;
  const std::vector<std::optional<Quadric>>& quadrics;
  std::vector<Candidate>& out;

  // The cylinder of the given radius on q's axis, over [lo, hi] along it.
  CsgTree cylinderOver(const Quadric& q, double radius, double lo, double hi) const {
    return CsgTree::leaf(Cylinder{q.axisPoint + 0.5 * (lo + hi) * q.axis, q.axis, radius, hi - lo});
  }

  // A cylinder extended to the cap plane beyond a chamfer.
  void addCappedCylinder(const Quadric& q, const Cylinder& cyl, int index, double support) {
    const auto lower = capPlane(ctx, q, cyl.radius, false, planes, quadrics);
    const auto upper = capPlane(ctx, q, cyl.radius, true, planes, quadrics);
    if (!lower && !upper) return;
    const double lo = lower ? lower->first : q.extent.lo;
    const double hi = upper ? upper->first : q.extent.hi;
    std::vector<int> used{index};
    if (lower) used.push_back(static_cast<int>(lower->second));
    if (upper) used.push_back(static_cast<int>(upper->second));
    out.push_back(makeCandidate(cylinderOver(q, cyl.radius, lo, hi), CandidateOrigin::Quadric,
                                std::move(used), support));
    ++stats.extendedCylinders;
  }

  // A cylinder whose end meets no fitted plane may go on, unseen, inside
  // another solid that bounds it (a knob's body under its dome, a pin in
  // a ball): the same cylinder run out to the scan's extent along its
  // axis at each such end, for an intersection to cut.
  void addOpenEndCylinder(const Quadric& q, const Cylinder& cyl, int index, double support) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& p : ctx.scan.points) {
      const double t = (p - q.axisPoint).dot(q.axis);
      lo = std::min(lo, t), hi = std::max(hi, t);
    }
    if (q.capped[0]) lo = q.extent.lo;
    if (q.capped[1]) hi = q.extent.hi;
    if (hi - lo > q.extent.size() + ctx.voxel) {
      out.push_back(makeCandidate(cylinderOver(q, cyl.radius, lo, hi), CandidateOrigin::Quadric,
                                  {index}, support));
      ++stats.extendedCylinders;
    }
  }

  // The additional box: the maximal box of a quarter cylinder, else the
  // minimal oriented bounding box of the patch. For a patch of a surface of
  // revolution that is the minimal box with one axis on the surface's axis
  // (exact, by rotating calipers; CGAL's search on such patches finds boxes
  // up to 3 % larger, and only on a wide full cone a tilted box 9 % smaller,
  // which would hide that the box is the cone's own); for a sphere patch,
  // CGAL's optimal oriented bounding box.
  Box additionalBox(const Quadric& q) {
    if (const auto* cyl = q.primitive.as<Cylinder>()) {
      double start = 0.0, coverage = 0.0;
      angularSpan(q, start, coverage);
      if (std::abs(coverage - 0.5 * kPi) <= ctx.options.quarterTolerance * kPi / 180.0) {
        ++stats.quarterCylinders;
        return quarterBox(ctx, q, cyl->radius, start, coverage, snapPlanes);
      }
    }
    return q.axial ? axialMinimalBox(q)
                   : boxAround(searchedBoxFrame(q.points, ctx.options.seed), q.points, q.sigma);
  }

  // The additional box of q, it less and intersected with q, and Fayolle's
  // separating planes: the faces of the box, bounding it, unless the plane
  // was fitted already. None for a flat box or one that is q's own bounds.
  void addBoxCandidates(const Quadric& q, int index, double support) {
    const Box box = additionalBox(q);
    if (!(box.halfSize.minCoeff() > 1e-6 * ctx.diagonal)) return;
    // Both boxes are estimated from the noisy patch: compare within its noise too.
    if (isOwnBoundingBox(box, q.primitive, ctx.lengthTol + 2.0 * q.sigma, ctx.cosParallel)) {
      ++stats.ownBoundsDropped;
      return;
    }
    const CsgTree additional = CsgTree::leaf(box);
    const CsgTree quadric = CsgTree::leaf(q.primitive);
    out.push_back(makeCandidate(additional, CandidateOrigin::Additional, {index}, support));
    out.push_back(makeCandidate(CsgTree::subtract({additional, quadric}), CandidateOrigin::Indirect,
                                {index}, support));
    out.push_back(makeCandidate(CsgTree::intersect({additional, quadric}),
                                CandidateOrigin::Indirect, {index}, support));
    for (int k = 0; k < 3; ++k) {
      for (double side : {1.0, -1.0}) {
        const Vec3 n = side * box.axes.col(k);
        const Vec3 face = box.center + box.halfSize[k] * n;
        if (isFittedPlane(ctx, n, face, planes)) continue;
        out.push_back(makeCandidate(CsgTree::leaf(HalfSpace{n, n.dot(face)}),
                                    CandidateOrigin::Separator, {index}, support));
      }
    }
  }

  // Every candidate of surface s's bounded quadric q.
  void addAll(const Quadric& q, std::size_t s) {
    const double support = static_cast<double>(ctx.surfaces[s].inliers.size());
    const int index = static_cast<int>(s);
    out.push_back(
        makeCandidate(CsgTree::leaf(q.primitive), CandidateOrigin::Quadric, {index}, support));
    if (ctx.options.axialBands) {
      for (const Band& band : axialBands(ctx, q, snapPlanes)) {
        out.push_back(makeCandidate(CsgTree::leaf(band.primitive), CandidateOrigin::Quadric,
                                    {index}, static_cast<double>(band.inliers)));
        ++stats.axialBands;
      }
    }
    if (const auto* cyl = q.primitive.as<Cylinder>()) {
      if (ctx.options.extendToCaps) addCappedCylinder(q, *cyl, index, support);
      if (ctx.options.extendOpenEnds && !(q.capped[0] && q.capped[1]))
        addOpenEndCylinder(q, *cyl, index, support);
    }
    // Fayolle: a cylinder with the torus' major radius over the patch's extent.
    if (const auto* torus = q.primitive.as<Torus>()) {
      const double height =
          q.extent.size() > 1e-6 * ctx.diagonal ? q.extent.size() : 2.0 * torus->minorRadius;
      const double mid =
          q.extent.size() > 1e-6 * ctx.diagonal ? 0.5 * (q.extent.lo + q.extent.hi) : 0.0;
      out.push_back(makeCandidate(
          CsgTree::leaf(Cylinder{q.axisPoint + mid * q.axis, q.axis, torus->majorRadius, height}),
          CandidateOrigin::Separator, {index}, support));
    }
    addBoxCandidates(q, index, support);
  }
};

}  // namespace

std::vector<Candidate> quadricCandidates(const Context& ctx, HypothesisStats& stats) {
  std::vector<Candidate> out;
  const std::vector<PlaneInfo> planes = planeInfos(ctx), noPlanes;
  // The planes that ends and quarter boxes snap onto (none without snapping).
  const std::vector<PlaneInfo>& snapPlanes = ctx.options.snapToPlanes ? planes : noPlanes;
  const std::vector<std::optional<Quadric>> quadrics = boundedQuadrics(ctx, planes, stats);
  QuadricCandidates candidates{ctx, stats, planes, snapPlanes, quadrics, out};
  for (std::size_t s = 0; s < ctx.surfaces.size(); ++s) {
    if (quadrics[s]) candidates.addAll(*quadrics[s], s);
  }
  return out;
}

}  // namespace csgvox::hypotheses_detail
