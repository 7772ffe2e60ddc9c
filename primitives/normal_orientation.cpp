#include "primitives/normal_orientation.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <queue>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "core/statistics.h"

namespace csgvox {
namespace {

// Neighbours whose normals are within this angle (sign ignored) lie on one
// smooth patch.
constexpr double kSmoothCosine = 0.906;  // cos 25 degrees
// Every normal of a patch lies within this angle of its first point's.
constexpr double kPatchConeCosine = 0.766;  // cos 40 degrees
// A neighbour lies across the tangent plane (the other face of a thin wall)
// when its offset along the normal exceeds this fraction of its distance and
// kAcrossNoise times the noise. A curved face's neighbours at distance d lie
// d / 2R off the plane, so faces of radius above 3.3 spacings stay whole.
constexpr double kAcrossFraction = 0.15;
constexpr double kAcrossNoise = 3.0;
// Occupancy cells are this many median point spacings wide (fine enough to
// tell the two faces of a wall three spacings thick apart); each point fills
// the cells within kFillSpacing of its own spacing.
constexpr double kCellSpacings = 1.0;
constexpr double kFillSpacing = 0.6;
constexpr int kMaxCellsPerAxis = 400;
// Rays per side: along the normal, and four tilted by kRayTilt radians.
constexpr double kRayTilt = std::numbers::pi / 6.0;
constexpr int kRaysPerSide = 5;
// Rays start this many cells plus the point's fill and kAcrossNoise times the
// noise from it: clear of its own layer.
constexpr double kStartCells = 1.0;
// Escape rays: this many directions evenly over the sphere, those within
// acos(kEscapeMinCosine) of the normal or its opposite.
constexpr int kEscapeDirections = 96;
constexpr double kEscapeMinCosine = 0.5;
// A neighbour with a parallel normal lies on a face across the tangent plane
// when its offset along the normal exceeds this fraction of its distance (and
// kAcrossNoise times the noise).
constexpr double kParallelFaceFraction = 0.25;
// The noise level is this quantile of the neighbourhoods' residuals (on a
// part with thin walls, each over its own face where it spans both).
constexpr double kNoiseQuantile = 0.2;
// On a part with thin walls, offsets along a normal that jump by more than
// this many times the noise level separate the faces of a wall.
constexpr double kSheetGapNoise = 3.0;
// A sheet holds at least this many of a neighbourhood's points (fewer
// beyond a gap are the tail of the noise or stray points).
constexpr std::ptrdiff_t kSheetMinPoints = 3;
// Two sheets show where the largest gap between a neighbourhood's offsets
// is more than this many times their spread on either side of it.
constexpr double kSheetGapSpread = 3.0;
// A patch's points near each other lie on one sheet: offsets along the
// patch's first normal above this fraction of their distance (a face
// within kPatchConeCosine of it turns them by at most 0.64) and
// kSheetGapNoise times the noise mean a fold.
constexpr double kFoldFraction = 0.75;
// A patch holds both faces of a thin wall when at least this fraction of
// its points, and kFoldedPoints, see another of its points across a gap
// (on another face). Measured on the bundled parts' scanner scans (their
// scan_scanner.ply and the scanner model's seeds 1 and 2): 46-49 % on the
// tray's most folded patch, 26 % on the sheet bracket's scan_scanner.ply
// (its seed-1 and seed-2 scans stay below); on the other parts at most 1 %
// of a patch with 50 or more such points (countersunk_plate: the tails of
// its noise), 3.6 % of one with 10 or more, and up to 40 % of a few of
// 40-150 points (pin_base's head: 48 of 144 on its scan_scanner.ply).
constexpr double kFoldedFraction = 0.04;
constexpr std::size_t kFoldedPoints = 50;
// Exact points (sampled from a mesh or a tree, not scanned) have no noise to
// tell a second sheet by: any edge or curvature in a neighbourhood leaves a
// gap more than kSheetGapSpread times a spread of zero. Their noise over one
// face, a rounding error, is below this fraction of the spacing, and they
// are not searched for thin walls. (With the search, the estimated normals
// of InverseCSG 129 and 060 sampled from their meshes went from 2.7 % and
// 5.0 % inward to 17 % and 11 %; 150, whose walls are thinner than its
// neighbourhoods, reads a face noise of 0.12 of the spacing and keeps it.)
constexpr double kExactNoise = 1e-6;
// Points that cast rays, at most (a deterministic stride over the points).
constexpr std::size_t kVisibilitySamples = 12000;
// A patch's sign is decided by visibility when its mean vote (in -1..1, see
// Votes) is at least this in magnitude.
constexpr double kDecisiveVote = 0.35;
// An undecided patch takes a decided neighbour's side only from a patch
// whose vote sum is at least this many times the square root of its votes
// (the spread of a sum of random votes of +-1): the walls of a hole through
// a face never seen, where a few small patches vote clearly the wrong way,
// give none. Measured: 3 to 5 give the same normals on the bundled bearing
// housing's scanner scan and the flange's raw scan with an unseen face.
constexpr double kSeedSignificance = 4.0;
// ... and only when the decided neighbours agree on this fraction of the
// edges joining them to the cluster.
constexpr double kClusterAgreement = 0.9;
// A patch nothing else decides takes its side from decided faces across a
// thin gap when at least this many of its points' neighbours there agree
// (sidesAcrossThinGaps), over at most kAcrossRounds rounds.
constexpr double kAcrossMinVotes = 5.0;
constexpr double kAcrossLateral = 1.0;
constexpr int kAcrossRounds = 8;
struct Hoods {
  std::span<const std::uint32_t> indices;
  unsigned k;
  const std::uint32_t* of(std::size_t i) const { return indices.data() + i * k; }
};

/// A neighbourhood's split into the point's own sheet and, where a wall
/// thinner than the neighbourhood shows, its other face: offsets along the
/// point's normal (from the point) below `low` or above `high` lie on the
/// other face. `residual` is the RMS of the own sheet's offsets.
struct SheetSplit {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
  double residual = 0.0;
  double wholeResidual = 0.0;  ///< the RMS of all the offsets
  bool twoSheets = false;      ///< the largest gap splits the neighbourhood
  bool across(double offset) const { return offset < low || offset > high; }
};

/// Splits a neighbourhood's sorted offsets (the point's own, 0, among them)
/// at the largest gap between them when both sides hold kSheetMinPoints
/// and the gap is more than kSheetGapSpread times their pooled spread:
/// noise on one face leaves no such gap, the two faces of a thin wall do.
SheetSplit splitSheets(const std::vector<double>& offset) {
  const auto sumSquares = [](auto first, auto last) {
    const double n = double(last - first);
    double sum = 0.0, sum2 = 0.0;
    for (auto it = first; it != last; ++it) sum += *it;
    const double mean = sum / n;
    for (auto it = first; it != last; ++it) sum2 += (*it - mean) * (*it - mean);
    return sum2;
  };
  // The residual: RMS distance to the point's tangent plane.
  const auto meanSquare = [](auto first, auto last) {
    double sum2 = 0.0;
    for (auto it = first; it != last; ++it) sum2 += *it * *it;
    return sum2 / double(last - first);
  };
  const std::size_t n = offset.size();
  SheetSplit split;
  split.residual = split.wholeResidual = std::sqrt(meanSquare(offset.begin(), offset.end()));
  const std::size_t m = std::size_t(kSheetMinPoints);
  if (n < 2 * m) return split;
  std::size_t gap = m - 1;  // offset[gap] and offset[gap + 1] are the widest apart
  for (std::size_t l = m; l + m < n; ++l) {
    if (offset[l + 1] - offset[l] > offset[gap + 1] - offset[gap]) gap = l;
  }
  const auto cut = offset.begin() + std::ptrdiff_t(gap + 1);
  const double pooled =
      std::sqrt((sumSquares(offset.begin(), cut) + sumSquares(cut, offset.end())) / double(n));
  if (offset[gap + 1] - offset[gap] <= kSheetGapSpread * pooled) return split;
  const bool ownBelow = offset[gap] >= 0.0;  // the point lies below the gap
  (ownBelow ? split.high : split.low) = 0.5 * (offset[gap] + offset[gap + 1]);
  split.residual =
      std::sqrt(ownBelow ? meanSquare(offset.begin(), cut) : meanSquare(cut, offset.end()));
  split.twoSheets = true;
  return split;
}

/// Noise level: a low quantile (kNoiseQuantile) of the neighbourhoods' RMS
/// distances to their tangent planes, over their own sheets or (`whole`)
/// over all their points.
double typicalResidual(std::span<const SheetSplit> splits, bool whole = false) {
  std::vector<double> residual(splits.size());
  for (std::size_t i = 0; i < splits.size(); ++i) {
    residual[i] = whole ? splits[i].wholeResidual : splits[i].residual;
  }
  const auto at = residual.begin() + std::ptrdiff_t(kNoiseQuantile * double(residual.size() - 1));
  std::nth_element(residual.begin(), at, residual.end());
  return *at;
}

/// Where a neighbourhood's offsets (sorted, the point's own 0 among them)
/// jump by more than `gap` above or below the point, the points beyond
/// the first such jump on either side lie on other sheets: a thin wall's
/// other face, or both walls beside a rim narrower than the neighbourhood.
void cutAtGaps(const std::vector<double>& sorted, double gap, SheetSplit& split) {
  const auto own = std::lower_bound(sorted.begin(), sorted.end(), 0.0);
  for (auto it = own; sorted.end() - (it + 1) >= kSheetMinPoints; ++it) {
    if (it[1] - it[0] > gap) {
      split.high = 0.5 * (it[0] + it[1]);
      break;
    }
  }
  for (auto it = own; it - sorted.begin() >= kSheetMinPoints; --it) {
    if (it[0] - it[-1] > gap) {
      split.low = 0.5 * (it[0] + it[-1]);
      break;
    }
  }
}

/// A point's neighbours' offsets along its normal, sorted.
void sortedOffsets(std::span<const Vec3> points, std::span<const Vec3> normals, const Hoods& hoods,
                   std::size_t i, std::vector<double>& offset) {
  offset.resize(hoods.k);
  for (unsigned l = 0; l < hoods.k; ++l) {
    offset[l] = normals[i].dot(points[hoods.of(i)[l]] - points[i]);
  }
  std::sort(offset.begin(), offset.end());
}

/// Each point's sheet split: splitSheets over its neighbourhood.
std::vector<SheetSplit> sheetSplits(std::span<const Vec3> points, std::span<const Vec3> normals,
                                    const Hoods& hoods) {
  std::vector<SheetSplit> splits(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size()), [&](const auto& range) {
    std::vector<double> offset;
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      sortedOffsets(points, normals, hoods, i, offset);
      splits[i] = splitSheets(offset);
    }
  });
  return splits;
}

/// Each point's cuts at the first jumps of more than `gap` on either side
/// of it (cutAtGaps: a rim between two faces has both beyond it), in place
/// of splitSheets' cut at the largest gap. A gap of 0 (a noise-free scan)
/// keeps splitSheets' cuts.
void cutSheets(std::span<const Vec3> points, std::span<const Vec3> normals, const Hoods& hoods,
               double gap, std::span<SheetSplit> splits) {
  if (gap <= 0.0) return;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size()), [&](const auto& range) {
    std::vector<double> offset;
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      sortedOffsets(points, normals, hoods, i, offset);
      splits[i].low = -std::numeric_limits<double>::infinity();
      splits[i].high = std::numeric_limits<double>::infinity();
      cutAtGaps(offset, gap, splits[i]);
    }
  });
}

/// Smooth patches: a label per point, and per patch its points.
struct Patches {
  std::vector<std::uint32_t> of;
  std::vector<std::vector<std::uint32_t>> points;
};

bool smoothEdge(const Vec3& p, const Vec3& np, const Vec3& q, const Vec3& nq, double noise) {
  if (std::abs(np.dot(nq)) < kSmoothCosine) return false;
  const Vec3 d = q - p;
  const double across = std::min(std::abs(np.dot(d)), std::abs(nq.dot(d)));
  return across <= std::max(kAcrossFraction * d.norm(), kAcrossNoise * noise);
}

/// Floods smooth patches from every point no patch holds yet, each within a
/// cone of normals around its first point's, making the normals consistent
/// within each (breadth-first from the patch's first point). With
/// `sheets`, a point joins a patch only if no patch point in its
/// neighbourhood lies on another face of a thin wall (see orientNormals).
void floodPatches(std::span<const Vec3> points, std::span<Vec3> normals, const Hoods& hoods,
                  std::span<const SheetSplit> splits, std::span<const Vec3> incoming, double noise,
                  bool sheets, Patches& patches) {
  const double foldGap = kSheetGapNoise * noise;
  // The splits' offsets are along the incoming normals.
  const auto sameSheet = [&](std::uint32_t i, std::uint32_t j) {
    const Vec3 d = points[j] - points[i];
    return !splits[i].across(incoming[i].dot(d)) && !splits[j].across(-incoming[j].dot(d));
  };
  const auto folds = [&](std::uint32_t seed, std::uint32_t j, std::uint32_t label) {
    for (unsigned m = 1; m < hoods.k; ++m) {
      const std::uint32_t o = hoods.of(j)[m];
      if (patches.of[o] != label) continue;
      if (!sameSheet(j, o)) return true;
      const Vec3 d = points[o] - points[j];
      const double along = std::abs(incoming[seed].dot(d));
      if (along > kFoldFraction * d.norm() && along > foldGap) {
        return true;
      }
    }
    return false;
  };
  const std::size_t n = points.size();
  std::vector<std::uint32_t> queue;
  for (std::uint32_t seed = 0; seed < n; ++seed) {
    if (patches.of[seed] != UINT32_MAX) continue;
    const auto label = static_cast<std::uint32_t>(patches.points.size());
    patches.points.emplace_back();
    queue.assign(1, seed);
    patches.of[seed] = label;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::uint32_t i = queue[head];
      for (unsigned l = 1; l < hoods.k; ++l) {
        const std::uint32_t j = hoods.of(i)[l];
        if (patches.of[j] != UINT32_MAX) continue;
        if (!smoothEdge(points[i], normals[i], points[j], normals[j], noise)) continue;
        if (sheets && (!sameSheet(i, j) || folds(seed, j, label))) continue;
        // Every normal of a patch stays near its first one, so the patch's
        // orientation cannot turn over along a chain of noisy normals.
        const double toSeed = normals[seed].dot(normals[j]);
        if (std::abs(toSeed) < kPatchConeCosine) continue;
        if (toSeed < 0.0) normals[j] = -normals[j];
        patches.of[j] = label;
        queue.push_back(j);
      }
    }
    patches.points.back() = queue;
  }
}

/// Whether a patch holds both faces of a thin wall: kFoldedFraction of its
/// points, and kFoldedPoints, see another of its points beyond the largest
/// gap of their neighbourhood (splitSheets).
bool holdsBothFaces(std::span<const Vec3> points, std::span<const Vec3> normals, const Hoods& hoods,
                    std::span<const SheetSplit> splits, const Patches& patches) {
  std::vector<std::size_t> folded(patches.points.size(), 0);
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    if (!splits[i].twoSheets) continue;
    for (unsigned l = 1; l < hoods.k; ++l) {
      const std::uint32_t j = hoods.of(i)[l];
      if (patches.of[j] == patches.of[i] &&
          splits[i].across(normals[i].dot(points[j] - points[i]))) {
        ++folded[patches.of[i]];
        break;
      }
    }
  }
  for (std::size_t p = 0; p < patches.points.size(); ++p) {
    if (folded[p] >= kFoldedPoints &&
        double(folded[p]) >= kFoldedFraction * double(patches.points[p].size())) {
      return true;
    }
  }
  return false;
}

/// Occupancy of a regular grid by the points, each filling the cells within
/// a fraction of its spacing.
class Occupancy {
 public:
  Occupancy(std::span<const Vec3> points, std::span<const double> spacing, double cell) {
    Aabb box;
    for (const Vec3& p : points) box.extend(p);
    cell_ = std::max(cell, box.size().maxCoeff() / kMaxCellsPerAxis);
    origin_ = box.min - Vec3::Constant(2.0 * cell_);
    for (int a = 0; a < 3; ++a) dims_[a] = int(std::ceil(box.size()[a] / cell_)) + 4;
    cells_.assign(std::size_t(dims_[0]) * dims_[1] * dims_[2], 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec3 r = Vec3::Constant(kFillSpacing * spacing[i]);
      const std::array<int, 3> lo = cellOf(points[i] - r), hi = cellOf(points[i] + r);
      for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int z = lo[2]; z <= hi[2]; ++z) cells_[index({x, y, z})] = 1;
    }
  }

  double cell() const { return cell_; }

  /// How many layers of occupied cells the ray from `from` along the unit
  /// `dir`, starting `start` away, crosses before it leaves the grid,
  /// counting no further than `limit` (1: does it meet any surface at all).
  int crossings(const Vec3& from, const Vec3& dir, double start,
                int limit = std::numeric_limits<int>::max()) const {
    const double step = 0.5 * cell_;
    int count = 0;
    bool inside = false;
    for (double t = start; count < limit; t += step) {
      const Vec3 c = (from + t * dir - origin_) / cell_;
      if (c.x() < 0 || c.y() < 0 || c.z() < 0 || c.x() >= dims_[0] || c.y() >= dims_[1] ||
          c.z() >= dims_[2]) {
        return count;
      }
      const bool occupied = cells_[index({int(c.x()), int(c.y()), int(c.z())})] != 0;
      if (occupied && !inside) ++count;
      inside = occupied;
    }
    return count;
  }

 private:
  std::array<int, 3> cellOf(const Vec3& p) const {
    std::array<int, 3> c;
    for (int a = 0; a < 3; ++a) {
      c[a] = std::clamp(int(std::floor((p[a] - origin_[a]) / cell_)), 0, dims_[a] - 1);
    }
    return c;
  }
  std::size_t index(const std::array<int, 3>& c) const {
    return (std::size_t(c[2]) * dims_[1] + c[1]) * dims_[0] + c[0];
  }

  double cell_ = 0.0;
  Vec3 origin_;
  std::array<int, 3> dims_{};
  std::vector<unsigned char> cells_;
};

/// Where neighbour j, its normal parallel to point i's (kSmoothCosine, sign
/// ignored), lies across i's tangent plane (its offset along i's normal
/// over kParallelFaceFraction of their distance and kAcrossNoise times the
/// noise): that offset, the other face of a thin wall or slot. 0 otherwise.
double parallelFaceAcross(std::span<const Vec3> points, std::span<const Vec3> normals,
                          std::size_t i, std::size_t j, double noise) {
  if (std::abs(normals[i].dot(normals[j])) < kSmoothCosine) return 0.0;
  const Vec3 d = points[j] - points[i];
  const double offset = normals[i].dot(d);
  return std::abs(offset) > std::max(kParallelFaceFraction * d.norm(), kAcrossNoise * noise)
             ? offset
             : 0.0;
}

/// Per patch: the sum of its sampled points' visibility votes and their
/// count. A point's vote is, over its rays on both sides, +1 for each ray
/// that crosses the surface an even number of times on the side of its
/// normal or an odd number on the other, -1 otherwise, over the ray count.
struct Votes {
  std::vector<double> sum;
  std::vector<std::size_t> count;
};

Votes visibilityVotes(std::span<const Vec3> points, std::span<const Vec3> normals,
                      const Patches& patches, std::span<const double> spacing, double medianSpacing,
                      double noise, const Hoods& hoods) {
  const std::size_t n = points.size();
  const Occupancy grid(points, spacing, kCellSpacings * medianSpacing);
  const std::size_t stride = std::max<std::size_t>(1, n / kVisibilitySamples);
  const std::size_t samples = (n + stride - 1) / stride;
  // Escape directions: a Fibonacci lattice on the sphere.
  std::vector<Vec3> dirs;
  for (int d = 0; d < kEscapeDirections; ++d) {
    const double z = 1.0 - (2.0 * d + 1.0) / kEscapeDirections;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = d * std::numbers::pi * (3.0 - std::sqrt(5.0));
    dirs.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  std::vector<double> vote(samples);
  tbb::parallel_for(std::size_t{0}, samples, [&](std::size_t s) {
    const std::size_t i = s * stride;
    const Vec3& nrm = normals[i];
    const Vec3 t1 = nrm.unitOrthogonal();
    const Vec3 t2 = nrm.cross(t1);
    const double start =
        kStartCells * grid.cell() + kFillSpacing * spacing[i] + kAcrossNoise * noise;
    // A face of a thin wall or slot: a parallel face lies across the tangent
    // plane on one side, nearer than the grid resolves; that side's rays
    // would jump it, so only the other side's rays vote.
    bool across[2] = {false, false};
    for (unsigned l = 1; l < hoods.k; ++l) {
      const std::uint32_t j = hoods.of(i)[l];
      if (const double offset = parallelFaceAcross(points, normals, i, j, noise); offset != 0.0) {
        across[offset > 0 ? 0 : 1] = true;
      }
    }
    const bool skip[2] = {across[0] && !across[1], across[1] && !across[0]};
    // A ray that meets no surface at all is the clearest sign of outside:
    // where rays escape on one side only, that side is outside (a surface
    // inside a concavity or a bore, whose parity rays may pass unseen walls,
    // is seen from outside through its opening). Escapes on both sides mean
    // a face the scanner never saw lets rays out of the material: parity
    // decides.
    bool escaped[2] = {false, false};
    for (const Vec3& d : dirs) {
      const double c = d.dot(nrm);
      const int sideIndex = c > 0 ? 0 : 1;
      if (std::abs(c) < kEscapeMinCosine || skip[sideIndex] || escaped[sideIndex]) continue;
      escaped[sideIndex] = grid.crossings(points[i], d, start, 1) == 0;
      if (escaped[0] && escaped[1]) break;
    }
    if (escaped[0] != escaped[1]) {
      vote[s] = escaped[0] ? 1.0 : -1.0;
      return;
    }
    int score = 0;
    int rays = 0;
    for (double side : {1.0, -1.0}) {
      if (skip[side > 0 ? 0 : 1]) continue;
      rays += kRaysPerSide;
      for (int r = 0; r < kRaysPerSide; ++r) {
        Vec3 dir = side * nrm;
        if (r > 0) {
          const double phi = (r - 1) * std::numbers::pi / 2.0;
          dir = std::cos(kRayTilt) * dir +
                std::sin(kRayTilt) * (std::cos(phi) * t1 + std::sin(phi) * t2);
        }
        // A ray that crosses the surface an even number of times ends
        // where it started: outside when it leaves the grid.
        const bool even = grid.crossings(points[i], dir.normalized(), start) % 2 == 0;
        score += even ? int(side) : -int(side);
      }
    }
    vote[s] = double(score) / rays;
  });
  Votes votes;
  votes.sum.assign(patches.points.size(), 0.0);
  votes.count.assign(patches.points.size(), 0);
  for (std::size_t s = 0; s < samples; ++s) {
    const std::uint32_t p = patches.of[s * stride];
    votes.sum[p] += vote[s];
    ++votes.count[p];
  }
  return votes;
}

/// The side of patches that nothing decides firmly, from a firmly decided
/// face close across their tangent plane: the other face of a thin wall or
/// of a narrow slot, nearer than the occupancy grid resolves, so that the
/// parity rays count the wall's two faces as one crossing and the escape
/// rays jump it; such faces, seen at grazing angles, also fall into patches
/// of a few points whose few rays decide nothing. A neighbour j of point i,
/// with a parallel normal, lying across i's tangent plane (kParallelFaceFraction
/// of their distance and kAcrossNoise times the noise) and nearly straight
/// across (within kAcrossLateral of the offset sideways: beside a step, the
/// upper face's points lie off to one side), tells which of the two it is:
/// where j's outward normal points away from i, the gap between them is
/// material (a wall) and i's outward normal points away from j; where it
/// points towards i, the gap is air (a slot) and i's normal points towards
/// j. A patch takes the side its points' such neighbours imply when at least
/// kAcrossMinVotes of them agree (kClusterAgreement); the patches so decided
/// are firm for the next round (a sheet whose inner face is split into small
/// patches is decided from its decided faces inwards).
void sidesAcrossThinGaps(std::span<const Vec3> points, std::span<const Vec3> normals,
                         const Hoods& hoods, const Patches& patches, double noise,
                         std::vector<int>& sign, std::vector<char>& firm) {
  const std::size_t count = patches.points.size();
  for (int round = 0; round < kAcrossRounds; ++round) {
    std::vector<int> next(sign);
    std::vector<char> nextFirm(firm);
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t p) {
      if (firm[p]) return;
      double keep = 0.0, flip = 0.0;
      for (std::uint32_t i : patches.points[p]) {
        const Vec3& ni = normals[i];
        for (unsigned l = 1; l < hoods.k; ++l) {
          const std::uint32_t j = hoods.of(i)[l];
          const std::uint32_t pj = patches.of[j];
          if (!firm[pj]) continue;
          const double offset = parallelFaceAcross(points, normals, i, j, noise);
          const Vec3 d = points[j] - points[i];
          if (offset == 0.0 || (d - offset * ni).norm() > kAcrossLateral * std::abs(offset)) {
            continue;
          }
          const bool wall = sign[pj] * normals[j].dot(d) > 0.0;  // j's outside faces away from i
          // i keeps its normal when it points away from j across a wall, or
          // towards j across a slot.
          ((offset < 0.0) == wall ? keep : flip) += 1.0;
        }
      }
      const double total = keep + flip;
      if (total < kAcrossMinVotes || std::max(keep, flip) < kClusterAgreement * total) return;
      next[p] = keep >= flip ? 1 : -1;
      nextFirm[p] = 1;
    });
    const bool changed = nextFirm != firm;
    sign.swap(next);
    firm.swap(nextFirm);
    if (!changed) break;
  }
}

/// Each patch's side: +1 (its normals stay), -1 (they flip) or 0 (nothing
/// decides it; it keeps the incoming normals). A patch whose points vote
/// clearly (kDecisiveVote) takes that side. The undecided patches joined
/// by smooth edges (a curved face that the patches' cones split) form
/// clusters; a cluster takes the side its decided neighbours imply across
/// those edges (two patches' relative side: the majority of their edges',
/// whether the two points' normals agree) when those neighbours' votes are
/// significant (kSeedSignificance) and agree (kClusterAgreement, weighted
/// by the edges), and the cluster's own votes, too weak to decide, do not
/// lean the other way. Otherwise the cluster keeps the incoming normals.
std::vector<int> patchSigns(std::span<const Vec3> points, std::span<const Vec3> normals,
                            const Hoods& hoods, const Patches& patches, const Votes& votes,
                            double noise, bool thinWalls) {
  const std::size_t count = patches.points.size();
  std::vector<int> sign(count, 0);
  // Firm: decided by significant votes (kSeedSignificance), or by a cluster.
  std::vector<char> firm(count, 0);
  const auto significant = [&](std::size_t p) {
    return std::abs(votes.sum[p]) >= kSeedSignificance * std::sqrt(double(votes.count[p]));
  };
  for (std::size_t p = 0; p < count; ++p) {
    const double mean = votes.count[p] ? votes.sum[p] / double(votes.count[p]) : 0.0;
    if (std::abs(mean) >= kDecisiveVote) sign[p] = mean < 0.0 ? -1 : 1;
    firm[p] = sign[p] != 0 && significant(p);
  }
  // The smooth edges between two patches: (lower patch, higher patch,
  // +1 where the normals agree, -1 where they are opposite).
  std::vector<std::tuple<std::uint32_t, std::uint32_t, int>> edges;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    const std::uint32_t a = patches.of[i];
    for (unsigned l = 1; l < hoods.k; ++l) {
      const std::uint32_t j = hoods.of(i)[l];
      const std::uint32_t b = patches.of[j];
      if (b <= a) continue;  // each pair once: from the lower patch's points only
      if (!smoothEdge(points[i], normals[i], points[j], normals[j], noise)) continue;
      edges.emplace_back(a, b, normals[i].dot(normals[j]) > 0.0 ? 1 : -1);
    }
  }
  std::sort(edges.begin(), edges.end());
  struct Link {
    std::uint32_t other;
    int net;  // edges whose normals agree less those whose normals are opposite
  };
  std::vector<std::vector<Link>> links(count);
  for (std::size_t e = 0; e < edges.size();) {
    const auto [a, b, unused] = edges[e];
    int net = 0;
    for (; e < edges.size() && std::get<0>(edges[e]) == a && std::get<1>(edges[e]) == b; ++e) {
      net += std::get<2>(edges[e]);
    }
    if (net == 0) continue;
    links[a].push_back({b, net});
    links[b].push_back({a, net});
  }
  // Clusters of undecided patches, each patch's side relative to its
  // cluster's first (widest link first; ties by the lower target, then the
  // lower source).
  std::vector<std::uint32_t> cluster(count, UINT32_MAX);
  std::vector<int> relative(count, 0);
  std::vector<std::vector<std::uint32_t>> members;
  // |net|, ~target, ~source, the target's side relative to the first.
  using Step = std::tuple<int, std::uint32_t, std::uint32_t, int>;
  std::priority_queue<Step> queue;
  const auto reach = [&](std::uint32_t from) {
    for (const Link& link : links[from]) {
      if (sign[link.other] == 0 && cluster[link.other] == UINT32_MAX) {
        queue.emplace(std::abs(link.net), ~link.other, ~from,
                      link.net > 0 ? relative[from] : -relative[from]);
      }
    }
  };
  for (std::uint32_t first = 0; first < count; ++first) {
    if (sign[first] != 0 || cluster[first] != UINT32_MAX) continue;
    const auto c = static_cast<std::uint32_t>(members.size());
    members.push_back({first});
    cluster[first] = c;
    relative[first] = 1;
    reach(first);
    while (!queue.empty()) {
      const std::uint32_t target = ~std::get<1>(queue.top());
      const int side = std::get<3>(queue.top());
      queue.pop();
      if (cluster[target] != UINT32_MAX) continue;
      cluster[target] = c;
      relative[target] = side;
      members[c].push_back(target);
      reach(target);
    }
  }
  for (const std::vector<std::uint32_t>& cl : members) {
    double weight[2] = {0.0, 0.0};  // for the cluster's first patch keeping, flipping
    for (std::uint32_t u : cl) {
      for (const Link& link : links[u]) {
        const std::uint32_t d = link.other;
        if (sign[d] == 0 || !significant(d)) continue;
        const int implied = sign[d] * (link.net > 0 ? 1 : -1) * relative[u];
        weight[implied > 0 ? 0 : 1] += std::abs(link.net);
      }
    }
    const double total = weight[0] + weight[1];
    if (total == 0.0 || std::max(weight[0], weight[1]) < kClusterAgreement * total) continue;
    const int side = weight[0] >= weight[1] ? 1 : -1;
    // The cluster's own votes, too weak to decide, must not lean the other way.
    double own = 0.0;
    for (std::uint32_t u : cl) own += relative[u] * votes.sum[u];
    if (own * side < 0.0) continue;
    for (std::uint32_t u : cl) {
      sign[u] = side * relative[u];
      firm[u] = 1;
    }
  }
  if (thinWalls) sidesAcrossThinGaps(points, normals, hoods, patches, noise, sign, firm);
  return sign;
}

}  // namespace

void orientNormals(std::span<const Vec3> points, std::span<Vec3> normals,
                   std::span<const std::uint32_t> neighbours, unsigned k, bool thinWalls) {
  const std::size_t n = points.size();
  if (normals.size() != n || neighbours.size() != n * std::size_t(k) || k < 2) {
    throw std::invalid_argument("orientNormals: sizes of points, normals, neighbours disagree");
  }
  if (n == 0) return;
  const Hoods hoods{neighbours, k};
  const std::vector<Vec3> provisional(normals.begin(), normals.end());
  std::vector<SheetSplit> splits = sheetSplits(points, normals, hoods);
  double noise = typicalResidual(splits, true);
  Patches patches;
  patches.of.assign(n, UINT32_MAX);
  floodPatches(points, normals, hoods, splits, provisional, noise, false, patches);
  // Spacing: the radius of a point's neighbourhood over sqrt(k / pi).
  std::vector<double> spacing(n);
  for (std::size_t i = 0; i < n; ++i) {
    spacing[i] = (points[hoods.of(i)[k - 1]] - points[i]).norm() * std::sqrt(std::numbers::pi / k);
  }
  std::vector<double> sorted(spacing);
  const double medianSpacing = median(sorted);
  const double faceNoise = typicalResidual(splits);
  if (faceNoise > kExactNoise * medianSpacing &&
      holdsBothFaces(points, provisional, hoods, splits, patches)) {
    // Thin walls: the noise is measured on their faces one at a time, and
    // the patches are flooded again with the faces kept apart.
    noise = faceNoise;
    cutSheets(points, provisional, hoods, kSheetGapNoise * noise, splits);
    std::copy(provisional.begin(), provisional.end(), normals.begin());
    patches = Patches{};
    patches.of.assign(n, UINT32_MAX);
    floodPatches(points, normals, hoods, splits, provisional, noise, true, patches);
  }
  const Votes votes =
      visibilityVotes(points, normals, patches, spacing, medianSpacing, noise, hoods);
  const std::vector<int> sign =
      patchSigns(points, normals, hoods, patches, votes, noise, thinWalls);
  for (std::size_t p = 0; p < patches.points.size(); ++p) {
    for (std::uint32_t i : patches.points[p]) {
      if (sign[p] == 0) {
        normals[i] = provisional[i];  // a patch nothing decides keeps its orientation
      } else if (sign[p] < 0) {
        normals[i] = -normals[i];
      }
    }
  }
}

}  // namespace csgvox
