#include "primitives/normal_estimation.h"

#include <CGAL/Eigen_svd.h>
#include <CGAL/Default_diagonalize_traits.h>
#include <CGAL/Monge_via_jet_fitting.h>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/nearest_neighbors.h"
#include "core/principal_axes.h"
#include "core/statistics.h"
#include "primitives/cgal_kernel.h"
#include "primitives/normal_orientation.h"

namespace csgvox {
namespace {

// Neighbourhoods of up to this many points have their jets fitted on
// fixed-capacity matrices (jetNormal); larger ones by CGAL's general fitting.
constexpr int kJetMaxPoints = 64;
// Degree of the jet (a quadric, as CGAL's jet_estimate_normals by default).
constexpr std::size_t kJetDegree = 2;

// A neighbourhood spans a surface when its second principal variance exceeds
// this fraction of its first (else it is a line up to rounding, and a jet
// fitted to it would be meaningless).
constexpr double kLineVarianceRatio = 1e-12;

/// True when the points spread in two directions, beyond rounding.
bool spansSurface(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& hood) {
  const Vec3 variances = principalAxes(points, hood).variances;
  return variances[0] > 0.0 && variances[1] > kLineVarianceRatio * variances[0];
}

void checkJetPoints(std::size_t n) {
  if (n < 6) {
    throw std::invalid_argument("a jet of degree 2 needs at least 6 points (has " +
                                std::to_string(n) + ")");
  }
}

}  // namespace

Vec3 generalJetNormal(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& hood) {
  checkJetPoints(hood.size());
  std::vector<cgal::Point3> local;
  local.reserve(hood.size());
  for (std::uint32_t j : hood) local.emplace_back(points[j].x(), points[j].y(), points[j].z());
  CGAL::Monge_via_jet_fitting<cgal::Kernel, cgal::Kernel, CGAL::Eigen_svd> fit;
  const cgal::Vector3 normal = fit(local.begin(), local.end(), kJetDegree, 1).normal_direction();
  return Vec3(normal.x(), normal.y(), normal.z()).normalized();
}

// As CGAL's Monge_via_jet_fitting with jet degree 2 and Monge degree 1: the
// same sums and diagonalisation for the principal frame, the same
// preconditioned system; on fixed-capacity matrices (no allocation per
// point, where the general fitting allocates about ten times), solved by a
// QR where the system has full rank.
Vec3 jetNormal(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& hood) {
  checkJetPoints(hood.size());
  if (!spansSurface(points, hood)) return Vec3::Zero();
  const int n = int(hood.size());
  if (n > kJetMaxPoints) return generalJetNormal(points, hood);
  double sumX = 0.0, sumY = 0.0, sumZ = 0.0, sumX2 = 0.0, sumY2 = 0.0, sumZ2 = 0.0;
  double sumXY = 0.0, sumXZ = 0.0, sumYZ = 0.0;
  for (std::uint32_t j : hood) {
    const double x = points[j].x(), y = points[j].y(), z = points[j].z();
    sumX += x / n;
    sumY += y / n;
    sumZ += z / n;
    sumX2 += x * x / n;
    sumY2 += y * y / n;
    sumZ2 += z * z / n;
    sumXY += x * y / n;
    sumXZ += x * z / n;
    sumYZ += y * z / n;
  }
  const std::array<double, 6> covariance = {
      sumX2 - sumX * sumX, sumXY - sumX * sumY, sumXZ - sumX * sumZ,
      sumY2 - sumY * sumY, sumYZ - sumY * sumZ, sumZ2 - sumZ * sumZ};
  std::array<double, 3> values{};
  std::array<double, 9> vectors{};
  CGAL::Default_diagonalize_traits<double, 3>::diagonalize_selfadjoint_covariance_matrix(
      covariance, values, vectors);
  // Axes by decreasing variance; the sign of the first does not change the
  // normal (x and a_x both flip).
  const Eigen::Vector3d e0(vectors[6], vectors[7], vectors[8]);
  const Eigen::Vector3d e1(vectors[3], vectors[4], vectors[5]);
  const Eigen::Vector3d e2(vectors[0], vectors[1], vectors[2]);
  // The points in that frame, the first at the origin: x and y go into
  // the system's linear columns, to be scaled once the preconditioning (the
  // mean of |x| and |y|) is known.
  using System = Eigen::Matrix<double, Eigen::Dynamic, 6, 0, kJetMaxPoints, 6>;
  using Rhs = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kJetMaxPoints, 1>;
  System m(n, 6);
  Rhs z(n);
  const Vec3& origin = points[hood[0]];
  double precond = 0.0;
  for (int r = 0; r < n; ++r) {
    const Eigen::Vector3d d = points[hood[std::size_t(r)]] - origin;
    m(r, 1) = e0.dot(d);
    m(r, 2) = e1.dot(d);
    z(r) = e2.dot(d);
    precond += std::abs(m(r, 1)) + std::abs(m(r, 2));
  }
  precond /= 2.0 * n;
  const double p2 = precond * precond;
  for (int r = 0; r < n; ++r) {
    const double x = m(r, 1), y = m(r, 2);
    m(r, 0) = 1.0;
    m(r, 1) = x / precond;
    m(r, 2) = y / precond;
    m(r, 3) = x * x / (2.0 * p2);
    m(r, 4) = x * y / p2;
    m(r, 5) = y * y / (2.0 * p2);
  }
  // A full-rank system (nearly always) has one least-squares solution,
  // which a QR gives at a fraction of the SVD's cost; a rank-deficient one
  // takes the SVD's least-norm solution, as CGAL's.
  Eigen::Matrix<double, 6, 1> a;
  const Eigen::ColPivHouseholderQR<System> qr(m);
  if (qr.rank() == 6) {
    a = qr.solve(z);
  } else {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(m),
                                                Eigen::ComputeThinU | Eigen::ComputeThinV);
    a = svd.solve(Eigen::VectorXd(z));
  }
  const double ax = a(1) / precond, ay = a(2) / precond;
  return (-ax * e0 - ay * e1 + e2).normalized();
}

namespace {

using namespace cgal;  // Kernel, Point3, Vector3

// Closest point pairs that decide how a piece is oriented against the
// largest piece.
constexpr std::size_t kMatchingPairs = 16;

// A point lies on a tangent plane when closer to it than this fraction of
// its neighbourhood radius, or than this multiple of the typical distance
// of neighbourhoods to their planes (noise).
constexpr double kOnPlaneRadiusFraction = 0.1;
constexpr double kOnPlaneNoiseFactor = 3.0;
// A normal agrees with its local surface within this angle (normalAgreement).
constexpr double kAgreementDegrees = 30.0;
// Points on which normalAgreement measures the agreement, at most.
constexpr std::size_t kAgreementSamples = 4000;
// normalAgreement fits its plane to the points among kAgreementWidening x k
// nearest whose normals are within acos(kSameSideCosine) of the point's.
constexpr std::size_t kAgreementWidening = 3;
constexpr double kSameSideCosine = 0.3;
// A neighbourhood is flat when its least principal spread is at most this
// fraction of its middle one (median over the sampled points); otherwise
// normalAgreement doubles it, up to kAgreementMaxBall points, measuring it
// on kAgreementBudget / k points (at least kAgreementMinSamples).
constexpr double kFlatNeighbourhood = 0.25;
constexpr std::size_t kAgreementMaxBall = 6144;
constexpr std::size_t kAgreementBudget = 4000 * 19;
constexpr std::size_t kAgreementMinSamples = 250;
// dominantPlane counts a neighbour on a face's plane within this fraction of
// the neighbourhood's radius (or kOnPlaneNoiseFactor x the noise), and
// refuses triples whose sides' sine is below kCollinearSine.
constexpr double kFacePlaneRadiusFraction = 0.02;
constexpr double kCollinearSine = 0.1;
constexpr double kEdgeOffFactor = 4.0;
// twoSheetPlane: the two faces of a thin wall in one neighbourhood. The
// second sheet holds at least kWallMinOther points, both together kWallShare
// of the neighbourhood, at most kWallMaxStrays points lie on the second's
// side off both; the sheets lie kWallSeparation times their pooled spread
// apart; the second's narrower in-plane variance is at least
// kWallSheetWidth of its wider, its centroid within kWallCover of its RMS
// in-plane radius of the point, sideways.
constexpr std::size_t kWallMinOther = 3;
constexpr double kWallShare = 0.85;
constexpr int kWallMaxStrays = 1;
constexpr double kWallSeparation = 6.0;
constexpr double kWallSheetWidth = 0.1;
constexpr double kWallCover = 0.5;
// Searched where a point's neighbours lie off its tangent plane by more than
// this many times the face noise (the 20 % quantile of those residuals).
constexpr double kWallResidualFactor = 2.0;
// A scan has thin walls when this share of its points (of at most
// kWallGateSamples, a stride over the scan) shows two sheets. Measured: the
// bundled parts' scanner scans and the InverseCSG parts' without thin walls
// 0.3-1.7 % (edges), InverseCSG 150 16 %.
constexpr double kWallScanShare = 0.02;
constexpr std::size_t kWallGateSamples = 50000;
// A coarser subset of about kWallCoarseSamples points decides first when
// its share is below kWallScanShare / kWallCoarseMargin or above kWallScanShare
// x kWallCoarseMargin: at 1 % its binomial spread over 10 000 points is
// 0.1 %, far from the 2 % it would have to cross.
constexpr std::size_t kWallCoarseSamples = 10000;
constexpr double kWallCoarseMargin = 2.0;

/// The distinct positions of a scan in order of first appearance, and for
/// every point the index of its position.
struct DistinctPoints {
  std::vector<Vec3> points;
  std::vector<std::uint32_t> of;
};

DistinctPoints distinctPoints(const std::vector<Vec3>& points) {
  const std::size_t n = points.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    const Vec3 &p = points[a], &q = points[b];
    return std::tie(p.x(), p.y(), p.z(), a) < std::tie(q.x(), q.y(), q.z(), b);
  };
  std::sort(order.begin(), order.end(), less);
  // Each run of equal positions is represented by its first (lowest) index.
  std::vector<std::uint32_t> representative(n);
  for (std::size_t r = 0; r < n; ++r) {
    const bool same = r > 0 && points[order[r]] == points[order[r - 1]];
    representative[order[r]] = same ? representative[order[r - 1]] : order[r];
  }
  DistinctPoints d;
  d.of.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (representative[i] == i) {
      d.of[i] = static_cast<std::uint32_t>(d.points.size());
      d.points.push_back(points[i]);
    } else {
      d.of[i] = d.of[representative[i]];
    }
  }
  return d;
}

bool isUsable(const Vector3& n) {
  const double len2 = n.squared_length();
  return std::isfinite(len2) && len2 > 1e-24;
}

/// The k nearest neighbours of every point, the point itself first.
struct Neighbourhoods {
  unsigned k = 0;
  std::vector<std::uint32_t> indices;  ///< k per point
  std::vector<double> radius;          ///< distance to the k-th neighbour

  const std::uint32_t* of(std::size_t i) const { return indices.data() + i * k; }
};

/// For every (distinct) point: its k nearest neighbours, and the unit normal
/// of a jet fitted to its k + 1 nearest neighbours (as CGAL's
/// jet_estimate_normals, unoriented). Points whose neighbourhood spans no
/// surface (collinear) take the normal of the nearest point whose fit
/// succeeded.
/// @throw std::invalid_argument when no neighbourhood spans a surface.
Neighbourhoods fitJets(const std::vector<Vec3>& points, const NearestNeighbors& nn, unsigned k,
                       std::vector<Vector3>& normals) {
  const std::size_t n = points.size();
  Neighbourhoods hoods;
  hoods.k = k;
  hoods.indices.resize(n * k);
  hoods.radius.resize(n);
  normals.assign(n, CGAL::NULL_VECTOR);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
    std::vector<std::uint32_t> hood;
    std::vector<double> d2;
    for (std::size_t at = range.begin(); at != range.end(); ++at) {
      const std::size_t i = nn.order()[at];  // neighbours visited together: cache-friendly
      // (never short: n > k); the previous point's neighbours bound the
      // search (the same result)
      nn.kNearestWithin(points[i], k + 1, kNearestBound(points, points[i], hood, k + 1), hood, &d2);
      // Distinct points: the point itself is the only one at distance 0.
      std::iter_swap(hood.begin(), std::find(hood.begin(), hood.end(), std::uint32_t(i)));
      std::copy(hood.begin(), hood.begin() + k, hoods.indices.begin() + std::ptrdiff_t(i * k));
      hoods.radius[i] = std::sqrt(d2[k - 1]);
      const Vec3 unit = jetNormal(points, hood);  // zero where they span no surface
      const Vector3 normal(unit.x(), unit.y(), unit.z());
      if (isUsable(normal)) normals[i] = normal / std::sqrt(normal.squared_length());
    }
  });

  std::vector<std::uint32_t> good;
  std::vector<std::uint32_t> bad;
  for (std::uint32_t i = 0; i < n; ++i) (isUsable(normals[i]) ? good : bad).push_back(i);
  if (bad.empty()) return hoods;
  if (good.empty()) {
    throw std::invalid_argument(
        "estimateNormals: no surface can be fitted to the points (they lie on a line)");
  }
  std::vector<Vec3> goodPoints;
  goodPoints.reserve(good.size());
  for (std::uint32_t i : good) goodPoints.push_back(points[i]);
  const NearestNeighbors goodTree(goodPoints);
  for (std::uint32_t i : bad) normals[i] = normals[good[goodTree.nearest(points[i])]];
  return hoods;
}

/// The offsets of a neighbourhood's points (k indices, i first) from point
/// i, one array per coordinate: the same differences as `q - p`, so that the
/// planes through i, tried by the hundred per point, measure them in plain
/// loops over the arrays (the same products and sums as `n * (q - p)`).
struct HoodOffsets {
  std::vector<double> x, y, z;

  HoodOffsets(const std::vector<Point3>& points, const std::uint32_t* hood, unsigned k,
              const Point3& p)
      : x(k), y(k), z(k) {
    for (unsigned l = 0; l < k; ++l) {
      const Point3& q = points[hood[l]];
      x[l] = q.x() - p.x();
      y[l] = q.y() - p.y();
      z[l] = q.z() - p.z();
    }
  }
  unsigned size() const { return unsigned(x.size()); }
  Vector3 operator[](unsigned l) const { return Vector3(x[l], y[l], z[l]); }
  // Every neighbour's signed distance along `n` (as n * (q - p)) into `d`.
  void along(const Vector3& n, double* d) const {
    const double nx = n.x(), ny = n.y(), nz = n.z();
    const unsigned k = size();
    for (unsigned l = 0; l < k; ++l) d[l] = nx * x[l] + ny * y[l] + nz * z[l];
  }
};

/// Calls `f` with the unit normal of every plane through point i and two
/// of its neighbours (`offsets` from i), but nearly collinear triples (their
/// planes the rounding turns).
template <class F>
void forEachPlaneThrough(const HoodOffsets& offsets, const F& f) {
  const unsigned k = offsets.size();
  for (unsigned a = 1; a < k; ++a) {
    const Vector3 u = offsets[a];
    for (unsigned b = a + 1; b < k; ++b) {
      const Vector3 v = offsets[b];
      const Vector3 n = CGAL::cross_product(u, v);
      const double length = std::sqrt(n.squared_length());
      if (!(length > kCollinearSine * std::sqrt(u.squared_length() * v.squared_length()))) continue;
      f(n / length);
    }
  }
}

/// The plane through point `i` that holds most of its neighbourhood `hood`
/// (k indices, i first) within `tolerance`: every plane through i and two
/// neighbours is tried, and the best is refitted by least squares to the
/// points it holds, twice. Near an edge the blended fits tilt the normal by
/// a few degrees; this plane is the face's own. Empty when no plane holds at
/// least half of the neighbourhood (a point on a curved surface).
std::optional<Vector3> dominantPlane(const std::vector<Point3>& points, const std::uint32_t* hood,
                                     unsigned k, std::size_t i, double tolerance) {
  const Point3& p = points[i];
  const HoodOffsets offsets(points, hood, k, p);
  std::vector<double> along(k);
  int bestCount = 0;
  double bestSpread = 0.0;
  Vector3 best = CGAL::NULL_VECTOR;
  forEachPlaneThrough(offsets, [&](const Vector3& n) {
    int count = 0;
    double spread = 0.0;
    offsets.along(n, along.data());
    for (unsigned l = 0; l < k; ++l) {
      const double d = std::abs(along[l]);
      if (d <= tolerance) {
        ++count;
        spread += d;
      }
    }
    if (count > bestCount || (count == bestCount && spread < bestSpread)) {
      bestCount = count;
      bestSpread = spread;
      best = n;
    }
  });
  if (2 * bestCount < int(k)) return std::nullopt;
  // The neighbours the face leaves out must lie well off it, as across an
  // edge, not just beyond the tolerance, as on a curved surface.
  {
    std::vector<double> off;
    for (unsigned l = 1; l < k; ++l) {
      const double d = std::abs(best * (points[hood[l]] - p));
      if (d > tolerance) off.push_back(d);
    }
    if (!off.empty()) {
      std::nth_element(off.begin(), off.begin() + std::ptrdiff_t(off.size() / 2), off.end());
      if (off[off.size() / 2] < kEdgeOffFactor * tolerance) return std::nullopt;
    }
  }
  std::vector<Vec3> held;
  for (int round = 0; round < 2; ++round) {
    held.clear();
    for (unsigned l = 0; l < k; ++l) {
      if (std::abs(best * (points[hood[l]] - p)) <= tolerance || l == 0) {
        const Point3& q = points[hood[l]];
        held.emplace_back(q.x(), q.y(), q.z());
      }
    }
    if (held.size() < 3) break;
    const Vec3 axis = principalAxes(held).leastAxis();
    best = Vector3(axis.x(), axis.y(), axis.z());
  }
  return best;
}

/// The common normal of two parallel sheets that hold point `i`'s
/// neighbourhood `hood` (k indices, i first): the faces of a wall thinner
/// than the neighbourhood. The jet, fitted to both faces, tilts by up to 90
/// degrees where the point's own face holds the fewer points (a tube's
/// inner face seen through its ends). The candidate normals are those of
/// the planes through i and two neighbours and the neighbours' own jets
/// (`normals`: a point alone on its face among the other face's points);
/// for each, the points within `tolerance` of the plane through i form i's
/// sheet and those within `tolerance` of the others' median offset the
/// second, with at most kWallMaxStrays more on the second's side (between
/// or beyond: a face that goes on, as across an edge). The pair holding
/// most (then the least spread) is accepted when it holds kWallShare of
/// the neighbourhood, the second sheet kWallMinOther points, and the
/// sheets lie apart by kWallSeparation times their pooled RMS spread about
/// their planes; when the second spreads over its plane (kWallSheetWidth:
/// a face across an edge projects onto a line) and lies over the point
/// (kWallCover: beyond an edge it lies off to one side). The normal is the
/// least axis of both sheets' points, each about its own centroid.
std::optional<Vector3> twoSheetPlane(const std::vector<Point3>& points,
                                     const std::vector<Vector3>& normals, const std::uint32_t* hood,
                                     unsigned k, std::size_t i, double tolerance) {
  const Point3& p = points[i];
  const HoodOffsets offsets(points, hood, k, p);
  std::vector<double> rest;
  int bestCount = 0;
  Vector3 best = CGAL::NULL_VECTOR;
  double bestOffset = 0.0;
  double bestSpread = 0.0;
  std::vector<double> offset(k);
  // The fewest points the two sheets must hold to be accepted (kWallShare of k).
  int minCount = 0;
  while (double(minCount) < kWallShare * double(k)) ++minCount;
  const auto consider = [&](const Vector3& n) {
    int own = 0, above = 0;
    rest.clear();
    offsets.along(n, offset.data());
    for (unsigned l = 0; l < k; ++l) {
      const double d = offset[l];
      if (std::abs(d) <= tolerance) {
        ++own;
      } else {
        rest.push_back(d);
        above += d > 0.0;
      }
    }
    if (rest.size() < kWallMinOther) return;
    // The second sheet lies on one side (its points within the tolerance of
    // the median offset, itself beyond the tolerance), so it holds at most
    // the rest on the larger side: a plane that cannot reach the pair
    // accepted or the best so far is passed over (the same result).
    const int below = int(rest.size()) - above;
    if (own + std::max(above, below) < std::max(minCount, bestCount)) return;
    const auto middle = rest.begin() + std::ptrdiff_t(rest.size() / 2);
    std::nth_element(rest.begin(), middle, rest.end());
    const double mid = *middle;
    int other = 0, strays = 0;
    double spread = 0.0;
    for (const double d : offset) {
      if (std::abs(d) <= tolerance) {
        spread += std::abs(d);
      } else if (std::abs(d - mid) <= tolerance) {
        ++other;
        spread += std::abs(d - mid);
      } else if (d * mid > 0.0) {
        ++strays;  // between the sheets or beyond the second: a face that goes on
      }
    }
    if (other < int(kWallMinOther) || strays > kWallMaxStrays) return;
    if (own + other > bestCount || (own + other == bestCount && spread < bestSpread)) {
      bestCount = own + other;
      bestSpread = spread;
      best = n;
      bestOffset = mid;
    }
  };
  forEachPlaneThrough(offsets, consider);
  // A point alone on its face among the other face's points: no plane
  // through it and two of them is the faces', but their own jets are.
  for (unsigned l = 1; l < k; ++l) {
    if (isUsable(normals[hood[l]])) consider(normals[hood[l]]);
  }
  if (bestCount < minCount) return std::nullopt;
  // Both sheets about their own centroids, and their spread about their planes.
  std::vector<Vec3> sheet[2];
  for (unsigned l = 0; l < k; ++l) {
    const Point3& q = points[hood[l]];
    const double d = best * (q - p);
    const int s = std::abs(d) <= tolerance ? 0 : std::abs(d - bestOffset) <= tolerance ? 1 : -1;
    if (s >= 0) sheet[s].emplace_back(q.x(), q.y(), q.z());
  }
  std::vector<Vec3> centred;
  Vec3 centroid[2];
  for (int s = 0; s < 2; ++s) {
    centroid[s] = Vec3::Zero();
    for (const Vec3& q : sheet[s]) centroid[s] += q;
    centroid[s] /= double(sheet[s].size());
    for (const Vec3& q : sheet[s]) centred.push_back(q - centroid[s]);
  }
  const Vec3 axis = principalAxes(centred).leastAxis();
  double spread2 = 0.0;
  for (const Vec3& q : centred) spread2 += axis.dot(q) * axis.dot(q);
  const double spread = std::sqrt(spread2 / double(centred.size()));
  if (std::abs(axis.dot(centroid[1] - centroid[0])) < kWallSeparation * spread) return std::nullopt;
  // The second sheet spreads over the plane, as a face does; the points of
  // a face across an edge within the band project onto a line along it.
  const Vec3 u = axis.unitOrthogonal(), v = axis.cross(u);
  double suu = 0.0, suv = 0.0, svv = 0.0;
  for (const Vec3& q : sheet[1]) {
    const Vec3 c = q - centroid[1];
    suu += u.dot(c) * u.dot(c);
    suv += u.dot(c) * v.dot(c);
    svv += v.dot(c) * v.dot(c);
  }
  const double mean = 0.5 * (suu + svv);
  const double half = std::sqrt(0.25 * (suu - svv) * (suu - svv) + suv * suv);
  if (mean - half < kWallSheetWidth * (mean + half)) return std::nullopt;
  // ... and lies over the point, not off to one side of it as beyond an edge.
  const Vec3 pi(p.x(), p.y(), p.z());
  const Vec3 off = centroid[1] - pi;
  const double sideways2 = u.dot(off) * u.dot(off) + v.dot(off) * v.dot(off);
  if (sideways2 > kWallCover * kWallCover * (suu + svv) / double(sheet[1].size())) {
    return std::nullopt;
  }
  return Vector3(axis.x(), axis.y(), axis.z());
}

/// Sharpens normals near edges. The jet fit blends the normals of the faces
/// that meet at an edge for every point within a neighbourhood of it. Each
/// point therefore considers the tangent planes of its neighbours that pass
/// through it (within a tolerance) and takes the plane that holds most of its
/// neighbours, keeping its own when that is among the best. That plane is a
/// neighbour's jet, itself tilted by the face across the edge by a few
/// degrees -- enough for RANSAC to prefer a wide cylinder along a narrow
/// wall to its plane -- so where it leaves neighbours out, the point takes
/// dominantPlane's face instead, when one holds half of them. On smooth
/// surfaces a point's own plane holds every neighbour and nothing changes.
bool sharpenAtEdges(const std::vector<Point3>& points, std::vector<Vector3>& normals,
                    const Neighbourhoods& hoods) {
  const std::size_t n = points.size();
  const unsigned k = hoods.k;
  // Noise (or curvature) level of a typical point: the RMS distance of its
  // neighbours to its tangent plane. Edges are a minority.
  std::vector<double> residual(n);
  for (std::size_t i = 0; i < n; ++i) {
    double sum2 = 0.0;
    for (unsigned l = 0; l < k; ++l) {
      const double d = normals[i] * (points[hoods.of(i)[l]] - points[i]);
      sum2 += d * d;
    }
    residual[i] = std::sqrt(sum2 / k);
  }
  std::vector<double> ownResidual(residual);
  std::nth_element(residual.begin(), residual.begin() + static_cast<std::ptrdiff_t>(n / 2),
                   residual.end());
  const double typical = residual[n / 2];
  std::nth_element(residual.begin(), residual.begin() + static_cast<std::ptrdiff_t>(n / 5),
                   residual.end());
  const double faceNoise = residual[n / 5];

  // The faces of walls thinner than the neighbourhoods, where the scan has
  // such walls (kWallScanShare of its points).
  std::vector<std::optional<Vector3>> wall(n);
  std::vector<char> tried(n, 0);
  // Searches every stride-th point not searched yet; returns the share of
  // those points that show two sheets.
  const auto findWalls = [&](std::size_t stride) {
    const std::size_t samples = (n + stride - 1) / stride;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples, 64), [&](const auto& range) {
      for (std::size_t s = range.begin(); s != range.end(); ++s) {
        const std::size_t i = s * stride;
        if (tried[i]) continue;
        tried[i] = 1;
        if (!(ownResidual[i] > kWallResidualFactor * faceNoise)) continue;
        const double tolerance = std::max(kFacePlaneRadiusFraction * hoods.radius[i],
                                          kOnPlaneNoiseFactor * faceNoise);
        wall[i] = twoSheetPlane(points, normals, hoods.of(i), k, i, tolerance);
      }
    });
    std::size_t walls = 0;
    for (std::size_t s = 0; s < samples; ++s) walls += wall[s * stride].has_value();
    return double(walls) / double(samples);
  };
  // Whether the scan has thin walls, from deterministic subsets of points
  // first (most scans have none: the search costs more than the jets). The
  // coarse subset (a multiple of the fine one's stride) decides when its
  // share lies beyond a factor kWallCoarseMargin of kWallScanShare; else the
  // fine one does.
  const std::size_t stride = std::max<std::size_t>(1, n / kWallGateSamples);
  const std::size_t coarse = stride * std::max<std::size_t>(1, n / (stride * kWallCoarseSamples));
  double share = findWalls(coarse);
  if (coarse > stride && share >= kWallScanShare / kWallCoarseMargin &&
      share <= kWallScanShare * kWallCoarseMargin) {
    share = findWalls(stride);
  }
  const bool thinWalls = share >= kWallScanShare;
  if (thinWalls) {
    findWalls(1);
  } else {
    wall.assign(n, std::nullopt);
  }

  std::vector<Vector3> sharpened = normals;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const std::uint32_t* hood = hoods.of(i);
      const double tolerance =
          std::max(kOnPlaneRadiusFraction * hoods.radius[i], kOnPlaneNoiseFactor * typical);
      const double faceTolerance =
          std::max(kFacePlaneRadiusFraction * hoods.radius[i], kOnPlaneNoiseFactor * typical);
      // Neighbours within the tolerance of the plane through `origin` with
      // `normal`; the count stops, at `beat` or less, once it can no longer
      // exceed `beat`.
      auto support = [&](const Point3& origin, const Vector3& normal, int beat) {
        int count = 0, missed = 0;
        const int mayMiss = int(k) - beat - 1;
        for (unsigned l = 0; l < k; ++l) {
          if (std::abs(normal * (points[hood[l]] - origin)) <= tolerance) {
            ++count;
          } else if (++missed > mayMiss) {
            break;
          }
        }
        return count;
      };
      std::size_t chosen = i;
      int best = support(points[i], normals[i], -1);
      // No plane holds more than all k neighbours: where the point's own
      // does (most points: those of smooth faces), the search ends.
      for (unsigned c = 1; c < k && best < int(k); ++c) {
        const std::size_t j = hood[c];
        if (std::abs(normals[j] * (points[i] - points[j])) > tolerance) continue;
        const int count = support(points[j], normals[j], best);
        if (count > best) {
          best = count;
          chosen = j;
        }
      }
      sharpened[i] = normals[chosen];
      if (wall[i]) {
        sharpened[i] = *wall[i];
        continue;
      }
      if (best < int(k)) {
        if (const auto face = dominantPlane(points, hood, k, i, faceTolerance))
          sharpened[i] = *face;
      }
    }
  });
  normals = std::move(sharpened);
  return thinWalls;
}

/// How consistently the normals at p and q, on pieces of the scan separated
/// by a gap, are oriented: > 0 consistent, < 0 one should be flipped. Where
/// the gap runs along the surface, parallel normals agree; where it runs
/// across the surface (an edge, two walls facing each other), p and q must
/// lie on opposite sides of each other's tangent planes relative to the gap,
/// which holds both for free space and for material between them. (Within
/// a piece, where gaps are as small as the noise, the gap's direction means
/// nothing and only parallel normals count.)
double agreement(const Point3& p, const Vector3& np, const Point3& q, const Vector3& nq) {
  const Vector3 gap = q - p;
  const double length = std::sqrt(gap.squared_length());
  if (!(length > 0.0)) return np * nq;
  const Vector3 dir = gap / length;
  const double acrossP = np * dir;
  const double acrossQ = nq * dir;
  const double along = std::max(0.0, 1.0 - std::max(std::abs(acrossP), std::abs(acrossQ)));
  return along * (np * nq) - acrossP * acrossQ;
}

/// Weight of a neighbour-graph edge for orientation propagation: low when
/// the normals are parallel (their relative orientation is clear) and the
/// edge runs along the surface. Edges across the surface, such as those
/// jumping through a thin wall between parallel but oppositely oriented
/// faces, are penalised by how steeply they leave either tangent plane.
double edgeWeight(const Point3& p, const Vector3& np, const Point3& q, const Vector3& nq) {
  const Vector3 gap = q - p;
  const double length = std::sqrt(gap.squared_length());
  const double dot = std::abs(np * nq);
  if (!(length > 0.0)) return 1.0 - dot;
  const Vector3 dir = gap / length;
  return (1.0 - dot) + std::min(std::abs(np * dir), std::abs(nq * dir));
}

/// Orients normals consistently by propagating along a minimum spanning
/// forest of the k-neighbour graph (Hoppe et al. 1992, as in CGAL's
/// mst_orient_normals, but with edgeWeight instead of 1 - |n_i . n_j|: with
/// the classic weight, edges through thin walls cost nothing, and on the
/// noisy scans in data/ whole walls came out inverted). Returns the trees,
/// one per connected piece of the graph, each consistent within itself.
std::vector<std::vector<std::size_t>> orientAlongSpanningForest(const std::vector<Point3>& points,
                                                                std::vector<Vector3>& normals,
                                                                const Neighbourhoods& hoods) {
  const std::size_t n = points.size();
  struct Edge {
    double weight;
    std::uint32_t a, b;
    bool operator<(const Edge& o) const {
      return std::tie(weight, a, b) < std::tie(o.weight, o.a, o.b);
    }
  };
  // Every neighbour pair once: a pair both points hold is listed by the
  // lower (its second copy, the same edge, would join nothing). The weights
  // are symmetric, so the sorted list is the same whoever lists a pair.
  const unsigned k = hoods.k;
  std::vector<Edge> edges(n * (k - 1));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      for (unsigned c = 1; c < k; ++c) {
        const std::uint32_t j = hoods.of(i)[c];
        Edge& e = edges[i * (k - 1) + c - 1];
        const std::uint32_t* other = hoods.of(j);
        if (j < i && std::find(other + 1, other + k, std::uint32_t(i)) != other + k) {
          e = {0.0, j, j};  // listed by j
          continue;
        }
        e = {edgeWeight(points[i], normals[i], points[j], normals[j]),
             static_cast<std::uint32_t>(std::min<std::size_t>(i, j)),
             static_cast<std::uint32_t>(std::max<std::size_t>(i, j))};
      }
    }
  });
  edges.erase(std::remove_if(edges.begin(), edges.end(), [](const Edge& e) { return e.a == e.b; }),
              edges.end());
  // No two edges are equal: any sort gives the same order.
  tbb::parallel_sort(edges.begin(), edges.end());

  // Kruskal.
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<std::vector<std::uint32_t>> tree(n);
  for (const Edge& e : edges) {
    const std::uint32_t ra = find(e.a);
    const std::uint32_t rb = find(e.b);
    if (ra == rb) continue;
    parent[ra] = rb;
    tree[e.a].push_back(e.b);
    tree[e.b].push_back(e.a);
  }

  // Breadth-first propagation from the first point of each tree.
  std::vector<char> visited(n, 0);
  std::vector<char> flipped(n, 0);
  std::vector<std::vector<std::size_t>> pieces;
  for (std::size_t root = 0; root < n; ++root) {
    if (visited[root]) continue;
    std::vector<std::size_t>& piece = pieces.emplace_back(1, root);
    visited[root] = 1;
    for (std::size_t head = 0; head < piece.size(); ++head) {
      const std::size_t i = piece[head];
      for (std::uint32_t j : tree[i]) {
        if (visited[j]) continue;
        visited[j] = 1;
        const bool disagree = normals[i] * normals[j] < 0.0;
        flipped[j] = flipped[i] != disagree;
        piece.push_back(j);
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (flipped[i]) normals[i] = -normals[i];
  }
  return pieces;
}

/// Orients every piece but the largest like the largest, judged by the
/// closest point pairs between them.
void matchPieces(const std::vector<Point3>& points, std::vector<Vector3>& normals,
                 const std::vector<std::vector<std::size_t>>& pieces) {
  if (pieces.size() < 2) return;
  const auto largest =
      std::max_element(pieces.begin(), pieces.end(),
                       [](const auto& a, const auto& b) { return a.size() < b.size(); });
  std::vector<Vec3> largestPoints;
  largestPoints.reserve(largest->size());
  for (std::size_t i : *largest)
    largestPoints.emplace_back(points[i].x(), points[i].y(), points[i].z());
  const NearestNeighbors tree(largestPoints);
  for (auto piece = pieces.begin(); piece != pieces.end(); ++piece) {
    if (piece == largest) continue;
    std::vector<std::pair<double, double>> pairs;  // squared gap, agreement
    pairs.reserve(piece->size());
    for (std::size_t i : *piece) {
      double d2 = 0.0;
      const std::size_t j =
          (*largest)[tree.nearest(Vec3(points[i].x(), points[i].y(), points[i].z()), &d2)];
      pairs.emplace_back(d2, agreement(points[i], normals[i], points[j], normals[j]));
    }
    const std::size_t m = std::min(kMatchingPairs, pairs.size());
    std::partial_sort(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(m), pairs.end());
    double vote = 0.0;
    for (std::size_t p = 0; p < m; ++p) vote += pairs[p].second;
    if (vote < 0.0) {
      for (std::size_t i : *piece) normals[i] = -normals[i];
    }
  }
}

/// Flips every normal when, at the scan's extreme points along ±x, ±y, ±z,
/// the normals mostly point inwards.
void orientOutwards(const std::vector<Point3>& points, std::vector<Vector3>& normals) {
  const std::size_t n = points.size();
  const std::size_t m = std::clamp<std::size_t>(n / 100, 1, 20);  // extreme points per direction
  std::vector<std::size_t> order(n);
  int agree = 0;
  int disagree = 0;
  double total = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {1.0, -1.0}) {
      std::iota(order.begin(), order.end(), std::size_t{0});
      std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(m - 1),
                       order.end(), [&](std::size_t a, std::size_t b) {
                         return sign * points[a][axis] > sign * points[b][axis];
                       });
      double vote = 0.0;
      for (std::size_t i = 0; i < m; ++i) vote += sign * normals[order[i]][axis];
      vote /= static_cast<double>(m);
      if (vote > 0.0) ++agree;
      if (vote < 0.0) ++disagree;
      total += vote;
    }
  }
  if (disagree > agree || (disagree == agree && total < 0.0)) {
    for (Vector3& normal : normals) normal = -normal;
  }
}

}  // namespace

void estimateNormals(PointCloud& cloud, int neighbors) {
  if (neighbors < 6) {
    throw std::invalid_argument("estimateNormals: neighbors must be at least 6 (is " +
                                std::to_string(neighbors) + ")");
  }
  const std::size_t n = cloud.size();
  if (n <= static_cast<std::size_t>(neighbors)) {
    throw std::invalid_argument("estimateNormals: " + std::to_string(n) +
                                " points are too few for " + std::to_string(neighbors) +
                                " neighbours");
  }
  for (const Vec3& p : cloud.points) {
    if (!p.allFinite()) throw std::invalid_argument("estimateNormals: a point is not finite");
  }
  // Copies of a point (a common scanner artefact) would make degenerate
  // neighbourhoods: the normals are estimated on the distinct positions.
  const DistinctPoints distinct = distinctPoints(cloud.points);
  const std::size_t m = distinct.points.size();
  if (m == 1) {
    throw std::invalid_argument("estimateNormals: all " + std::to_string(n) +
                                " points are at the same position");
  }
  if (m <= static_cast<std::size_t>(neighbors)) {
    throw std::invalid_argument(
        "estimateNormals: " + std::to_string(m) + " distinct positions among " + std::to_string(n) +
        " points are too few for " + std::to_string(neighbors) + " neighbours");
  }
  const NearestNeighbors tree(distinct.points);
  std::vector<Vector3> normals;
  const Neighbourhoods hoods =
      fitJets(distinct.points, tree, static_cast<unsigned>(neighbors), normals);
  std::vector<Point3> points;
  points.reserve(m);
  for (const Vec3& p : distinct.points) points.emplace_back(p.x(), p.y(), p.z());
  const bool thinWalls = sharpenAtEdges(points, normals, hoods);
  matchPieces(points, normals, orientAlongSpanningForest(points, normals, hoods));
  orientOutwards(points, normals);
  std::vector<Vec3> unit(m);
  for (std::size_t i = 0; i < m; ++i) {
    unit[i] = Vec3(normals[i].x(), normals[i].y(), normals[i].z()).normalized();
  }
  orientNormals(distinct.points, unit, hoods.indices, hoods.k, thinWalls);

  cloud.normals.resize(n);
  for (std::size_t i = 0; i < n; ++i) cloud.normals[i] = unit[distinct.of[i]];
}

double normalAgreement(const PointCloud& cloud, int neighbors) {
  if (neighbors < 3) {
    throw std::invalid_argument("normalAgreement: neighbors must be at least 3 (is " +
                                std::to_string(neighbors) + ")");
  }
  if (!cloud.hasNormals()) throw std::invalid_argument("normalAgreement: the cloud has no normals");
  const std::size_t n = cloud.size();
  if (n <= static_cast<std::size_t>(neighbors)) return 1.0;
  const NearestNeighbors tree(cloud.points);
  const double cosTolerance = std::cos(kAgreementDegrees * std::numbers::pi / 180.0);
  // Where the points are dense against their noise, the nearest few form a
  // ball, not a patch of surface, and its plane turns at random: the
  // neighbourhood widens until its planes are flat (least spread under a
  // quarter of the middle one), on fewer points as it widens.
  std::size_t k = static_cast<std::size_t>(neighbors) + 1;
  while (true) {
    const std::size_t count =
        std::clamp<std::size_t>(kAgreementBudget / k, kAgreementMinSamples, kAgreementSamples);
    const std::size_t stride = std::max<std::size_t>(1, n / count);
    const std::size_t samples = (n + stride - 1) / stride;
    // Per sampled point: 1 agrees, 0 disagrees, -1 spans no surface; and
    // the flatness of its neighbourhood.
    std::vector<int> agrees(samples, -1);
    std::vector<double> flatness(samples, -1.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples, 16), [&](const auto& range) {
      std::vector<std::uint32_t> wide, hood;
      for (std::size_t s = range.begin(); s != range.end(); ++s) {
        const std::size_t i = s * stride;
        // The nearest points whose normals face the same way (within about
        // 70 degrees): the other face of a wall thinner than the
        // neighbourhood, and much of the face across a sharp edge, stay out
        // of the plane. Normals in random directions keep a random third of
        // the points, which still lie on the local surface.
        tree.kNearest(cloud.points[i], kAgreementWidening * k, wide);
        hood.clear();
        for (std::uint32_t j : wide) {
          if (hood.size() < k && cloud.normals[j].dot(cloud.normals[i]) > kSameSideCosine) {
            hood.push_back(j);
          }
        }
        if (hood.size() < 3 || !spansSurface(cloud.points, hood)) continue;
        const PrincipalAxes axes = principalAxes(cloud.points, hood);
        agrees[s] = std::abs(axes.leastAxis().dot(cloud.normals[i])) >=
                    cosTolerance * cloud.normals[i].norm();
        flatness[s] = std::sqrt(std::max(0.0, axes.variances[2]) / axes.variances[1]);
      }
    });
    std::erase_if(flatness, [](double f) { return f < 0.0; });
    const auto counted = std::count_if(agrees.begin(), agrees.end(), [](int a) { return a >= 0; });
    if (counted == 0) return 1.0;
    if (kAgreementWidening * k >= std::min(n, kAgreementMaxBall) ||
        median(std::move(flatness)) <= kFlatNeighbourhood) {
      return double(std::count(agrees.begin(), agrees.end(), 1)) / double(counted);
    }
    k *= 2;
  }
}

}  // namespace csgvox
