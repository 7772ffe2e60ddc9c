#pragma once
/// Ground-truth surfaces of a sampled CSG tree, and matching of primitive
/// hypotheses against the tree's primitives. Shared by the tests of the
/// hypothesis generator and of what consumes it.
///
/// Ground truth (no RANSAC): the tree is sampled with sampleSurface, which
/// records the leaf each point lies on. Each leaf's points are split into the
/// smooth pieces of its boundary by their noise-free positions: a box into
/// its six faces, a cylinder or cone into its lateral surface and two caps, a
/// half-space, sphere or torus into one piece. Every piece with at least
/// `minPoints` points becomes an exact Surface (the leaf's own parameters;
/// planes and curved surfaces oriented like the scan normals, `convex` from
/// the normals) whose inliers are those points and whose rms is measured on
/// the (possibly noisy) scan. Pieces with fewer points are not visible.
///
/// Matching. Only what the scan shows can be matched: a leaf is *observable*
/// when at least one of its pieces is visible, and its *visible samples* are
/// the noise-free positions of the points of its visible pieces. Hidden
/// extents (a hole's length past the faces it cuts, the far faces of a
/// subtracted box, the part of a boss buried in a plate) are free. A
/// candidate matches an observable leaf when it is a single primitive and
///  * it has the leaf's type (a half-space matches in either orientation:
///    intersecting with one is subtracting its complement);
///  * its axes are within `angleDeg` of the leaf's: the axis of a cylinder,
///    cone or torus (either sign), the normal of a half-space, and, for a
///    box, the outward normal of each visible face is parallel to one of the
///    candidate's axes;
///  * its observable sizes are within `length`·D (D: diagonal of the tree's
///    bounding box): cylinder radius; sphere centre and radius; torus centre
///    and both radii; cone half-angle (within `angleDeg`) and the cone's
///    radius at both ends of the visible lateral band; for a box, the
///    candidate face on the side of each visible face lies within
///    `length`·D of that face's plane;
///  * every visible sample p satisfies |f(p)| <= `length`·D for the
///    candidate's signed distance f (it lies on the candidate's surface).
/// Leaves that are not observable (entirely hidden, e.g. a fillet ring whose
/// every face the fillet torus removes) are reported, not matched.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/surface.h"
#include "mesh/surface_sampler.h"
#include "primitives/hypotheses.h"

namespace csgvox::test {

/// A sampled tree with its exact ground-truth surfaces.
struct GroundTruth {
  CsgTree tree;
  std::vector<const Node*> leaves;    ///< tree.leaves()
  PointCloud scan;                    ///< what the generator sees (noisy when noise > 0)
  std::vector<Vec3> clean;            ///< noise-free positions, same order as scan
  std::vector<std::uint32_t> source;  ///< leaf of each point
  double diagonal = 0.0;              ///< D: diagonal of the tree's bounding box
  std::vector<Surface> surfaces;      ///< visible pieces as exact surfaces
  std::vector<int> surfaceLeaf;       ///< leaf of each surface
  std::vector<int> surfacePiece;  ///< piece of the leaf: box face 2k + (side < 0); 0 lateral, 1 top
                                  ///< cap, 2 bottom cap
  std::vector<std::vector<std::uint32_t>> visible;  ///< per leaf: points of its visible pieces
};

namespace detail {

// Piece of a leaf's boundary that a noise-free point lies on.
inline int pieceOf(const Primitive& prim, const Vec3& p) {
  if (const auto* b = prim.as<Box>()) {
    const Vec3 local = b->axes.transpose() * (p - b->center);
    int best = 0;
    double bestGap = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const double gap = std::abs(b->halfSize[k] - std::abs(local[k]));
      if (gap < bestGap) bestGap = gap, best = 2 * k + (local[k] < 0.0 ? 1 : 0);
    }
    return best;
  }
  auto axial = [&](const Vec3& c, const Vec3& a, double h, double lateralGap) {
    const double z = (p - c).dot(a);
    const double capGap = std::abs(0.5 * h - std::abs(z));
    if (lateralGap <= capGap) return 0;
    return z > 0.0 ? 1 : 2;
  };
  if (const auto* c = prim.as<Cylinder>()) {
    const Vec3 d = p - c->center;
    const double rho = (d - d.dot(c->axis) * c->axis).norm();
    return axial(c->center, c->axis, c->height, std::abs(rho - c->radius));
  }
  if (const auto* c = prim.as<Cone>()) {
    const Vec3 d = p - c->center;
    const double z = d.dot(c->axis);
    const double rho = (d - z * c->axis).norm();
    const double r = c->radiusBottom + (c->radiusTop - c->radiusBottom) * (z / c->height + 0.5);
    const double slant = std::atan2(std::abs(c->radiusTop - c->radiusBottom), c->height);
    return axial(c->center, c->axis, c->height, std::abs(rho - r) * std::cos(slant));
  }
  return 0;
}

// The exact surface of one piece; `normalSum` is the sum of its points' scan
// normals, `radialSum` the sum of normal·(outward radial direction).
inline Surface pieceSurface(const Primitive& prim, int piece, const Vec3& normalSum,
                            double radialSum) {
  Surface s;
  auto plane = [&](const Vec3& outward, const Vec3& onPlane) {
    const bool flip = normalSum.dot(outward) < 0.0;
    const Vec3 n = flip ? Vec3(-outward) : outward;
    s.shape = PlaneSurface{n, n.dot(onPlane)};
  };
  if (const auto* h = prim.as<HalfSpace>()) {
    plane(h->normal, h->offset * h->normal);
  } else if (const auto* b = prim.as<Box>()) {
    const int k = piece / 2;
    const Vec3 n = (piece % 2 == 0 ? 1.0 : -1.0) * b->axes.col(k);
    plane(n, b->center + b->halfSize[k] * n);
  } else if (const auto* c = prim.as<Cylinder>()) {
    if (piece == 0) {
      s.shape = CylinderSurface{c->center, c->axis, c->radius};
    } else {
      const Vec3 n = piece == 1 ? c->axis : Vec3(-c->axis);
      plane(n, c->center + 0.5 * c->height * n);
    }
  } else if (const auto* c = prim.as<Cone>()) {
    if (piece == 0) {
      const bool widening = c->radiusTop > c->radiusBottom;
      const double rNear = widening ? c->radiusBottom : c->radiusTop;
      const double slope = std::abs(c->radiusTop - c->radiusBottom) / c->height;
      const Vec3 dir = widening ? c->axis : Vec3(-c->axis);
      const Vec3 nearEnd = c->center - 0.5 * c->height * dir;
      s.shape = ConeSurface{nearEnd - (rNear / slope) * dir, dir, std::atan(slope)};
    } else {
      const Vec3 n = piece == 1 ? c->axis : Vec3(-c->axis);
      plane(n, c->center + 0.5 * c->height * n);
    }
  } else if (const auto* c = prim.as<Sphere>()) {
    s.shape = SphereSurface{c->center, c->radius};
  } else if (const auto* c = prim.as<Torus>()) {
    s.shape = TorusSurface{c->center, c->axis, c->majorRadius, c->minorRadius};
  }
  s.convex = radialSum >= 0.0;
  return s;
}

// Outward "radial" direction of a curved piece at p (away from the axis,
// centre or tube centre); zero for planes.
inline Vec3 radialAt(const Primitive& prim, int piece, const Vec3& p) {
  auto fromAxis = [&](const Vec3& c, const Vec3& a) {
    const Vec3 d = p - c;
    return Vec3((d - d.dot(a) * a).normalized());
  };
  if (piece != 0) return Vec3::Zero();
  if (const auto* c = prim.as<Cylinder>()) return fromAxis(c->center, c->axis);
  if (const auto* c = prim.as<Cone>()) return fromAxis(c->center, c->axis);
  if (const auto* c = prim.as<Sphere>()) return (p - c->center).normalized();
  if (const auto* c = prim.as<Torus>()) {
    const Vec3 tube = c->center + c->majorRadius * fromAxis(c->center, c->axis);
    return (p - tube).normalized();
  }
  return Vec3::Zero();
}

inline double degrees(double cosine) {
  return std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

}  // namespace detail

/// Samples `tree` (noise-free and, with the same seed, with `noise` as a
/// fraction of D) and builds its ground-truth surfaces (see the file comment).
inline GroundTruth makeGroundTruth(const CsgTree& tree, std::size_t points = 20000,
                                   double noise = 0.0, std::uint64_t seed = 1,
                                   std::size_t minPoints = 30) {
  GroundTruth gt;
  gt.tree = tree;
  gt.leaves = tree.leaves();
  SampleOptions o;
  o.points = points;
  o.seed = seed;
  const SurfaceSample clean = sampleSurface(tree, o);
  gt.clean = clean.cloud.points;
  gt.source = clean.source;
  gt.diagonal = clean.diagonal;
  if (noise > 0.0) {
    o.noise = noise;
    gt.scan = sampleSurface(tree, o).cloud;  // same draws, then the noise
    // The clean positions must be the noisy points' own: check it.
    for (std::size_t i = 0; i < gt.clean.size(); ++i) {
      if ((gt.scan.points[i] - gt.clean[i]).norm() > 10.0 * noise * gt.diagonal) {
        throw std::logic_error(
            "makeGroundTruth: the sampler's noisy points no longer follow "
            "its clean ones for the same seed");
      }
    }
  } else {
    gt.scan = clean.cloud;
  }
  gt.visible.resize(gt.leaves.size());
  for (std::size_t leaf = 0; leaf < gt.leaves.size(); ++leaf) {
    const Primitive& prim = gt.leaves[leaf]->primitive;
    std::vector<std::vector<std::uint32_t>> pieces(6);
    for (std::uint32_t i = 0; i < gt.source.size(); ++i) {
      if (gt.source[i] == leaf)
        pieces[static_cast<std::size_t>(detail::pieceOf(prim, gt.clean[i]))].push_back(i);
    }
    for (int piece = 0; piece < 6; ++piece) {
      const auto& idx = pieces[static_cast<std::size_t>(piece)];
      if (idx.size() < minPoints) continue;
      Vec3 normalSum = Vec3::Zero();
      double radialSum = 0.0;
      for (std::uint32_t i : idx) {
        normalSum += gt.scan.normals[i];
        radialSum += gt.scan.normals[i].dot(detail::radialAt(prim, piece, gt.clean[i]));
      }
      Surface s = detail::pieceSurface(prim, piece, normalSum, radialSum);
      s.inliers = idx;
      double sq = 0.0;
      for (std::uint32_t i : idx) sq += std::pow(surfaceDistance(s, gt.scan.points[i]), 2);
      s.rms = std::sqrt(sq / static_cast<double>(idx.size()));
      gt.surfaces.push_back(std::move(s));
      gt.surfaceLeaf.push_back(static_cast<int>(leaf));
      gt.surfacePiece.push_back(piece);
      gt.visible[leaf].insert(gt.visible[leaf].end(), idx.begin(), idx.end());
    }
  }
  return gt;
}

/// Tolerances of matchLeaf.
struct MatchTolerances {
  double angleDeg = 2.0;  ///< axes, normals, cone half-angles
  double length = 0.01;   ///< sizes and sample distances, fraction of D
};

/// Result of matching one ground-truth leaf.
struct LeafMatch {
  bool observable = false;
  bool matched = false;
  int candidate = -1;  ///< index of the matching (or nearest) candidate
  double worstSample = std::numeric_limits<double>::infinity();  ///< largest |f| over the visible
                                                                 ///< samples, scan units
  std::string detail;  ///< why the nearest candidate failed, when not matched
};

/// Matches leaf `leaf` of the ground truth against the candidates (see the
/// file comment for the definition).
inline LeafMatch matchLeaf(const GroundTruth& gt, std::size_t leaf,
                           const std::vector<Candidate>& candidates,
                           const MatchTolerances& tol = {}) {
  LeafMatch result;
  const std::vector<std::uint32_t>& vis = gt.visible[leaf];
  result.observable = !vis.empty();
  if (!result.observable) return result;
  const Primitive& g = gt.leaves[leaf]->primitive;
  const double lenTol = tol.length * gt.diagonal;
  const double cosTol = std::cos(tol.angleDeg * std::numbers::pi / 180.0);
  // Up to 3000 visible samples, evenly spread.
  std::vector<Vec3> samples;
  const std::size_t step = std::max<std::size_t>(1, vis.size() / 3000);
  for (std::size_t i = 0; i < vis.size(); i += step) samples.push_back(gt.clean[vis[i]]);

  // Parameter check; returns an empty string when the candidate passes.
  auto check = [&](const Primitive& c) -> std::string {
    std::ostringstream why;
    auto parallel = [&](const Vec3& a, const Vec3& b, const char* what) {
      if (std::abs(a.dot(b)) < cosTol) {
        why << what << " off by " << detail::degrees(std::abs(a.dot(b))) << " deg; ";
      }
    };
    auto close = [&](double a, double b, const char* what) {
      if (std::abs(a - b) > lenTol) why << what << " off by " << std::abs(a - b) << "; ";
    };
    if (const auto* h = g.as<HalfSpace>()) {
      parallel(h->normal, c.as<HalfSpace>()->normal, "normal");
    } else if (const auto* b = g.as<Box>()) {
      const Box& cb = *c.as<Box>();
      for (std::size_t s = 0; s < gt.surfaces.size(); ++s) {
        if (gt.surfaceLeaf[s] != static_cast<int>(leaf)) continue;
        const int k = gt.surfacePiece[s] / 2;
        const Vec3 n = (gt.surfacePiece[s] % 2 == 0 ? 1.0 : -1.0) * b->axes.col(k);
        const Vec3 facePoint = b->center + b->halfSize[k] * n;
        int j = 0;
        for (int i = 1; i < 3; ++i) {
          if (std::abs(cb.axes.col(i).dot(n)) > std::abs(cb.axes.col(j).dot(n))) j = i;
        }
        if (std::abs(cb.axes.col(j).dot(n)) < cosTol) {
          why << "no axis along face " << gt.surfacePiece[s] << "; ";
          continue;
        }
        const double side = cb.axes.col(j).dot(n) > 0.0 ? 1.0 : -1.0;
        const Vec3 candidateFace = cb.center + side * cb.halfSize[j] * cb.axes.col(j);
        if (std::abs(n.dot(candidateFace - facePoint)) > lenTol) {
          why << "face " << gt.surfacePiece[s] << " off by "
              << std::abs(n.dot(candidateFace - facePoint)) << "; ";
        }
      }
    } else if (const auto* cy = g.as<Cylinder>()) {
      const Cylinder& cc = *c.as<Cylinder>();
      parallel(cy->axis, cc.axis, "axis");
      close(cy->radius, cc.radius, "radius");
    } else if (const auto* co = g.as<Cone>()) {
      const Cone& cc = *c.as<Cone>();
      parallel(co->axis, cc.axis, "axis");
      const double ga = std::atan(std::abs(co->radiusTop - co->radiusBottom) / co->height);
      const double ca = std::atan(std::abs(cc.radiusTop - cc.radiusBottom) / cc.height);
      if (std::abs(ga - ca) * 180.0 / std::numbers::pi > tol.angleDeg) {
        why << "half-angle off by " << std::abs(ga - ca) * 180.0 / std::numbers::pi << " deg; ";
      }
      // Radii at both ends of the visible lateral band.
      double zlo = std::numeric_limits<double>::infinity(), zhi = -zlo;
      for (std::size_t s = 0; s < gt.surfaces.size(); ++s) {
        if (gt.surfaceLeaf[s] != static_cast<int>(leaf) || gt.surfacePiece[s] != 0) continue;
        for (std::uint32_t i : gt.surfaces[s].inliers) {
          const double z = (gt.clean[i] - co->center).dot(co->axis);
          zlo = std::min(zlo, z), zhi = std::max(zhi, z);
        }
      }
      for (double z : {zlo, zhi}) {
        if (!std::isfinite(z)) continue;
        const Vec3 x = co->center + z * co->axis;
        const double rg =
            co->radiusBottom + (co->radiusTop - co->radiusBottom) * (z / co->height + 0.5);
        const double zc = (x - cc.center).dot(cc.axis);
        const double rc =
            cc.radiusBottom + (cc.radiusTop - cc.radiusBottom) * (zc / cc.height + 0.5);
        close(rg, rc, "radius at the band's end");
      }
    } else if (const auto* sp = g.as<Sphere>()) {
      const Sphere& cs = *c.as<Sphere>();
      close(0.0, (sp->center - cs.center).norm(), "centre");
      close(sp->radius, cs.radius, "radius");
    } else if (const auto* to = g.as<Torus>()) {
      const Torus& ct = *c.as<Torus>();
      parallel(to->axis, ct.axis, "axis");
      close(0.0, (to->center - ct.center).norm(), "centre");
      close(to->majorRadius, ct.majorRadius, "major radius");
      close(to->minorRadius, ct.minorRadius, "minor radius");
    }
    return why.str();
  };

  // The passing candidate with the smallest sample error; else the nearest miss.
  double bestPass = std::numeric_limits<double>::infinity();
  double bestMiss = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const Node& root = *candidates[k].tree.root();
    if (root.kind != NodeKind::Primitive || root.primitive.type() != g.type()) continue;
    const std::string why = check(root.primitive);
    double worst = 0.0;
    for (const Vec3& p : samples) worst = std::max(worst, std::abs(root.primitive.value(p)));
    if (why.empty() && worst <= lenTol) {
      if (worst < bestPass) {
        bestPass = worst;
        result.matched = true;
        result.candidate = static_cast<int>(k);
        result.worstSample = worst;
        result.detail.clear();
      }
      continue;
    }
    const double miss = (why.empty() ? 0.0 : 1e6 * gt.diagonal) + worst;
    if (!result.matched && miss < bestMiss) {
      bestMiss = miss;
      result.candidate = static_cast<int>(k);
      result.worstSample = worst;
      std::ostringstream d;
      d << why << "worst sample " << worst << " (tolerance " << lenTol << ")";
      result.detail = d.str();
    }
  }
  if (result.candidate < 0) {
    result.detail = std::string("no candidate of type ") + std::string(primitiveTypeName(g.type()));
  }
  return result;
}

}  // namespace csgvox::test
