// generateHypotheses: runs the cuboid and quadric generators, adds the
// half-spaces of unused planes, removes duplicates and applies the cap.
// Also the small geometric helpers the generators share.

#include "primitives/hypotheses.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>

#include "primitives/bounding_box.h"
#include "primitives/hypotheses_internal.h"

namespace csgvox {

namespace hypotheses_detail {

Range robustRange(std::vector<double> values, double sigma) {
  const auto [mn, mx] = std::minmax_element(values.begin(), values.end());
  Range r{*mn, *mx};
  const double extent = r.size();
  if (!(sigma > 0.0) || !(extent > 0.0)) return r;
  // Expected number of points of a uniformly sampled region (density n/extent)
  // pushed past a straight edge by noise of deviation sigma is
  // density·sigma/sqrt(2 pi). Trimming half of them leaves the extreme about
  // sigma/2 past a straight edge, and does not cut much into regions whose
  // density tapers towards the extreme (a corner, a curved end).
  const double n = static_cast<double>(values.size());
  auto k = static_cast<std::size_t>(0.5 * n * sigma / (extent * std::sqrt(2.0 * std::numbers::pi)));
  k = std::min(k, values.size() / 4);
  if (k == 0) return r;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  r.lo = values[k];
  const std::size_t top = values.size() - 1 - k;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(top), values.end());
  r.hi = values[top];
  return r;
}

Range denseRange(std::span<const double> values, Range range) {
  constexpr std::size_t kPerBin = 50, kMinValues = 800, kMaxBins = 256;
  if (values.size() < kMinValues || !(range.size() > 0.0)) return range;
  const std::size_t bins = std::min(kMaxBins, values.size() / kPerBin);
  const double width = range.size() / double(bins);
  std::vector<std::size_t> count(bins, 0);
  for (double v : values) {
    if (v < range.lo || v > range.hi) continue;
    ++count[std::min(bins - 1, static_cast<std::size_t>((v - range.lo) / width))];
  }
  std::vector<std::size_t> filled;
  for (std::size_t c : count) {
    if (c > 0) filled.push_back(c);
  }
  const auto mid = filled.begin() + static_cast<std::ptrdiff_t>(filled.size() / 2);
  std::nth_element(filled.begin(), mid, filled.end());
  const double sparse = 0.25 * double(*mid);
  // The patch starts at the first run of kRun dense bins: a single bin of a
  // tail can reach the threshold by chance (its count varies by its square
  // root), kRun in a row hardly.
  constexpr std::size_t kRun = 3;
  const auto denseRun = [&](std::size_t from, bool up) {
    for (std::size_t k = 0; k < kRun; ++k) {
      if (up ? from + k >= bins : k > from) return false;
      if (double(count[up ? from + k : from - k]) < sparse) return false;
    }
    return true;
  };
  std::size_t first = 0, last = bins - 1;
  while (first < last && !denseRun(first, true)) ++first;
  while (last > first && !denseRun(last, false)) --last;
  return Range{range.lo + double(first) * width, range.lo + double(last + 1) * width};
}

Mat3 searchedBoxFrame(std::span<const Vec3> points, std::uint32_t seed) {
  return minimalBoxFrame(points, MinimalBoxOptions{seed, kBoxSearchPoints});
}

Box boxFromRanges(const Mat3& frame, const std::array<Range, 3>& ranges) {
  Vec3 mid, half;
  for (int k = 0; k < 3; ++k) {
    mid[k] = 0.5 * (ranges[k].lo + ranges[k].hi);
    half[k] = 0.5 * ranges[k].size();
  }
  return Box{frame * mid, frame, half};
}

std::vector<PlaneRef> planeSurfaces(const Context& ctx) {
  std::vector<PlaneRef> planes;
  for (std::size_t s = 0; s < ctx.surfaces.size(); ++s) {
    const Surface& surface = ctx.surfaces[s];
    const PlaneSurface* plane = surface.as<PlaneSurface>();
    if (plane != nullptr && surface.inliers.size() >= kMinInliers) {
      planes.push_back({s, &surface, plane});
    }
  }
  return planes;
}

std::vector<Vec3> inlierPoints(const PointCloud& scan, const Surface& surface) {
  std::vector<Vec3> pts;
  pts.reserve(surface.inliers.size());
  for (std::uint32_t i : surface.inliers) pts.push_back(scan.points[i]);
  return pts;
}

ToleranceGrid::ToleranceGrid(std::size_t dimensions, double tolerance)
    : dims_(dimensions), tol_(std::max(tolerance, 1e-300)) {}

long long ToleranceGrid::cell(double v) const {
  return static_cast<long long>(std::floor(v / (2.0 * tol_)));
}

std::size_t ToleranceGrid::hash(const std::vector<long long>& key) {
  std::size_t h = 1469598103934665603ull;
  for (long long k : key) h = (h ^ static_cast<std::size_t>(k)) * 1099511628211ull;
  return h;
}

void ToleranceGrid::insert(std::span<const double> x, std::size_t id) {
  std::vector<long long> key(dims_);
  for (std::size_t k = 0; k < dims_; ++k) key[k] = cell(x[k]);
  cells_[hash(key)].push_back({key, id});
}

namespace {

bool nearLen(double a, double b, double tol) { return std::abs(a - b) <= tol; }

}  // namespace

bool samePrimitive(const Primitive& pa, const Primitive& pb, double tol, double cosTol) {
  if (pa.type() != pb.type()) return false;
  auto parallel = [cosTol](const Vec3& a, const Vec3& b) { return std::abs(a.dot(b)) >= cosTol; };
  auto nearPt = [tol](const Vec3& a, const Vec3& b) { return (a - b).norm() <= tol; };
  switch (pa.type()) {
    case PrimitiveType::HalfSpace: {
      const HalfSpace &a = *pa.as<HalfSpace>(), &b = *pb.as<HalfSpace>();
      const double c = a.normal.dot(b.normal);
      if (std::abs(c) < cosTol) return false;
      return nearLen(a.offset, c > 0.0 ? b.offset : -b.offset, tol);
    }
    case PrimitiveType::Box: {
      const Box &a = *pa.as<Box>(), &b = *pb.as<Box>();
      if (!nearPt(a.center, b.center)) return false;
      std::array<bool, 3> used{};
      for (int i = 0; i < 3; ++i) {
        bool found = false;
        for (int j = 0; j < 3 && !found; ++j) {
          if (used[j] || !parallel(a.axes.col(i), b.axes.col(j))) continue;
          if (!nearLen(a.halfSize[i], b.halfSize[j], tol)) return false;
          used[j] = found = true;
        }
        if (!found) return false;
      }
      return true;
    }
    case PrimitiveType::Cylinder: {
      const Cylinder &a = *pa.as<Cylinder>(), &b = *pb.as<Cylinder>();
      return parallel(a.axis, b.axis) && nearPt(a.center, b.center) &&
             nearLen(a.radius, b.radius, tol) && nearLen(a.height, b.height, tol);
    }
    case PrimitiveType::Cone: {
      const Cone &a = *pa.as<Cone>(), &b = *pb.as<Cone>();
      if (!parallel(a.axis, b.axis) || !nearPt(a.center, b.center) ||
          !nearLen(a.height, b.height, tol)) {
        return false;
      }
      const bool same = a.axis.dot(b.axis) > 0.0;
      return nearLen(a.radiusBottom, same ? b.radiusBottom : b.radiusTop, tol) &&
             nearLen(a.radiusTop, same ? b.radiusTop : b.radiusBottom, tol);
    }
    case PrimitiveType::Sphere: {
      const Sphere &a = *pa.as<Sphere>(), &b = *pb.as<Sphere>();
      return nearPt(a.center, b.center) && nearLen(a.radius, b.radius, tol);
    }
    case PrimitiveType::Torus: {
      const Torus &a = *pa.as<Torus>(), &b = *pb.as<Torus>();
      return parallel(a.axis, b.axis) && nearPt(a.center, b.center) &&
             nearLen(a.majorRadius, b.majorRadius, tol) &&
             nearLen(a.minorRadius, b.minorRadius, tol);
    }
  }
  return false;
}

}  // namespace hypotheses_detail

namespace {

using namespace hypotheses_detail;

bool sameNode(const Node& a, const Node& b, double tol, double cosTol) {
  if (a.kind != b.kind || a.children.size() != b.children.size()) return false;
  if (a.kind == NodeKind::Primitive) return samePrimitive(a.primitive, b.primitive, tol, cosTol);
  for (std::size_t i = 0; i < a.children.size(); ++i) {
    if (!sameNode(*a.children[i], *b.children[i], tol, cosTol)) return false;
  }
  return true;
}

// A point every duplicate of the tree has within the tolerance: the centre
// of its first bounded leaf; none for a half-space.
std::optional<Vec3> anchor(const Node& n) {
  if (n.kind != NodeKind::Primitive) return anchor(*n.children.front());
  return std::visit(
      [](const auto& s) -> std::optional<Vec3> {
        if constexpr (requires { s.center; }) {
          return s.center;
        } else {
          return std::nullopt;
        }
      },
      n.primitive.shape());
}

// D and the default voxel from the scan's minimal oriented bounding box.
void scanScale(const PointCloud& scan, std::uint32_t seed, double& diagonal, double& longest) {
  // An even subset is enough for the box's orientation; the extents use every point.
  const std::size_t step = std::max<std::size_t>(1, scan.size() / 20000);
  std::vector<Vec3> subset;
  for (std::size_t i = 0; i < scan.size(); i += step) subset.push_back(scan.points[i]);
  const Mat3 frame = searchedBoxFrame(subset, seed);
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& p : scan.points) {
    const Vec3 q = frame.transpose() * p;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  diagonal = (hi - lo).norm();
  longest = (hi - lo).maxCoeff();
}

void checkOptions(const HypothesisOptions& o) {
  auto angleOk = [](double deg) { return std::isfinite(deg) && deg >= 0.0 && deg < 45.0; };
  if (!(std::isfinite(o.voxelSize) && o.voxelSize >= 0.0)) {
    throw std::invalid_argument("hypotheses: voxelSize must be finite and >= 0");
  }
  if (!angleOk(o.parallelTolerance) || !angleOk(o.orthogonalTolerance) ||
      !angleOk(o.quarterTolerance)) {
    throw std::invalid_argument("hypotheses: angular tolerances must be in [0, 45) degrees");
  }
  if (!(std::isfinite(o.duplicateTolerance) && o.duplicateTolerance >= 0.0)) {
    throw std::invalid_argument("hypotheses: duplicateTolerance must be finite and >= 0");
  }
}

}  // namespace

std::string_view candidateOriginName(CandidateOrigin origin) {
  // In the enum's order.
  static constexpr std::array<std::string_view, kCandidateOriginCount> kNames{
      "cuboid", "quadric", "plane", "additional", "indirect", "separator"};
  const auto index = static_cast<std::size_t>(origin);
  return index < kNames.size() ? kNames[index] : "unknown";
}

std::size_t OriginCounts::total() const {
  std::size_t n = 0;
  for (std::size_t c : count) n += c;
  return n;
}

HypothesisSet generateHypotheses(const PointCloud& scan, std::span<const Surface> surfaces,
                                 const HypothesisOptions& options) {
  checkOptions(options);
  HypothesisSet out;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    for (std::uint32_t i : surfaces[s].inliers) {
      if (i >= scan.size()) {
        throw std::invalid_argument(
            "hypotheses: surface " + std::to_string(s) + " has inlier index " + std::to_string(i) +
            " outside the scan of " + std::to_string(scan.size()) + " points");
      }
    }
  }
  if (surfaces.empty() || scan.empty()) return out;

  double diagonal = 0.0, longest = 0.0;
  scanScale(scan, options.seed, diagonal, longest);
  Context ctx{scan, surfaces, options};
  ctx.diagonal = diagonal;
  ctx.voxel = options.voxelSize > 0.0 ? options.voxelSize : longest / 64.0;
  ctx.lengthTol = options.duplicateTolerance * diagonal;
  ctx.cosParallel = std::cos(options.parallelTolerance * std::numbers::pi / 180.0);
  ctx.sinOrthogonal = std::sin(options.orthogonalTolerance * std::numbers::pi / 180.0);
  HypothesisStats& stats = out.stats;
  stats.voxelSize = ctx.voxel;
  stats.diagonal = diagonal;

  std::vector<char> planeInCuboid(surfaces.size(), 0);
  std::vector<Candidate> all = cuboidCandidates(ctx, stats.cuboids, planeInCuboid);
  std::vector<Candidate> quadrics = quadricCandidates(ctx, stats);
  // Half-spaces of the planes no kept cuboid uses (wedge-like cuts, chamfers),
  // on the material side of the patch (its normal points out of the half-space).
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    const PlaneSurface* pl = surfaces[s].as<PlaneSurface>();
    if (pl == nullptr || planeInCuboid[s] || surfaces[s].inliers.size() < kMinInliers) continue;
    Candidate c;
    c.tree = CsgTree::leaf(HalfSpace{pl->normal.normalized(), pl->offset / pl->normal.norm()});
    c.origin = CandidateOrigin::Plane;
    c.surfaces = {static_cast<int>(s)};
    c.support = static_cast<double>(surfaces[s].inliers.size());
    all.push_back(std::move(c));
  }
  for (Candidate& c : quadrics) all.push_back(std::move(c));
  for (const Candidate& c : all) ++stats.generated[c.origin];

  // Priority: origin order, then support (stable: generation order on ties).
  std::stable_sort(all.begin(), all.end(), [](const Candidate& a, const Candidate& b) {
    if (a.origin != b.origin) return a.origin < b.origin;
    return a.support > b.support;
  });

  // Duplicates: same kind of tree, primitives equal within tolerance. Bounded
  // shapes are found by their centre, half-spaces (few) by a linear search.
  std::vector<Candidate> kept;
  ToleranceGrid grid(3, ctx.lengthTol);
  std::vector<std::size_t> halfSpaces;
  for (Candidate& c : all) {
    const Node& node = *c.tree.root();
    auto same = [&](std::size_t k) {
      return sameNode(*kept[k].tree.root(), node, ctx.lengthTol, ctx.cosParallel);
    };
    const std::optional<Vec3> at = anchor(node);
    const bool duplicate = at ? grid.any(std::span<const double>(at->data(), 3), same)
                              : std::any_of(halfSpaces.begin(), halfSpaces.end(), same);
    if (duplicate) {
      ++stats.duplicatesRemoved;
      continue;
    }
    if (at) {
      grid.insert(std::span<const double>(at->data(), 3), kept.size());
    } else {
      halfSpaces.push_back(kept.size());
    }
    kept.push_back(std::move(c));
  }
  for (const Candidate& c : kept) ++stats.afterDuplicates[c.origin];

  // Cap: cuboids, the only kind whose number grows combinatorially, go
  // first, worst supported first; then, if needed, the others by support.
  // The survivors keep the priority order.
  if (options.maxCandidates > 0 && kept.size() > options.maxCandidates) {
    std::vector<std::size_t> order(kept.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const bool ca = kept[a].origin == CandidateOrigin::Cuboid;
      const bool cb = kept[b].origin == CandidateOrigin::Cuboid;
      if (ca != cb) return cb;
      return kept[a].support > kept[b].support;
    });
    std::vector<char> keep(kept.size(), 0);
    for (std::size_t i = 0; i < options.maxCandidates; ++i) keep[order[i]] = 1;
    std::vector<Candidate> capped;
    for (std::size_t i = 0; i < kept.size(); ++i) {
      if (keep[i]) capped.push_back(std::move(kept[i]));
    }
    kept = std::move(capped);
    stats.capped = true;
  }
  for (const Candidate& c : kept) ++stats.returned[c.origin];
  out.candidates = std::move(kept);
  return out;
}

}  // namespace csgvox
