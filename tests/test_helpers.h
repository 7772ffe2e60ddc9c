#pragma once
/// Domain-level checks and generators shared by the csgvox tests: vector
/// comparison, tree equivalence by sampling, seeded random primitives and
/// trees, an independent point-in-solid test, parametric surface samples and
/// finite-difference gradients.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <source_location>
#include <sstream>
#include <string>
#include <vector>

#include "core/csg_tree.h"
#include "core/geometry.h"
#include "core/primitive.h"

namespace csgvox::test {

/// Deterministic random engine used by every test (seed is explicit).
using Rng = std::mt19937_64;

/// Text form of a vector for failure messages.
inline std::string str(const Vec3& v) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

/// Success when every coordinate of a and b differs by at most tol.
inline ::testing::AssertionResult vecNear(const Vec3& a, const Vec3& b, double tol) {
  const double err = (a - b).cwiseAbs().maxCoeff();
  if (err <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << str(a) << " and " << str(b) << " differ by " << err << " > " << tol;
}

/// Expects a and b to agree coordinate-wise within tol; failures are reported
/// at the caller's line.
inline void expectNear(const Vec3& a, const Vec3& b, double tol,
                       std::source_location loc = std::source_location::current()) {
  ::testing::ScopedTrace trace(loc.file_name(), static_cast<int>(loc.line()), "expectNear");
  EXPECT_TRUE(vecNear(a, b, tol));
}

/// Uniform double in [lo, hi).
inline double uniform(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

/// Uniform random unit vector.
inline Vec3 randomUnit(Rng& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 v;
  do {
    v = Vec3(n(rng), n(rng), n(rng));
  } while (v.norm() < 1e-3);
  return v.normalized();
}

/// Uniform random rotation (right-handed orthonormal columns).
inline Mat3 randomRotation(Rng& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// Uniform random point in a bounded box.
inline Vec3 randomPoint(Rng& rng, const Aabb& box) {
  Vec3 p;
  for (int i = 0; i < 3; ++i) p[i] = uniform(rng, box.min[i], box.max[i]);
  return p;
}

/// Volumetric IoU of two solids given as point-membership tests, estimated
/// on `samples` uniform random points of `box` (which must hold both).
template <class InA, class InB>
double sampledIou(const Aabb& box, InA&& inA, InB&& inB, int samples, std::uint64_t seed) {
  Rng rng(seed);
  std::size_t both = 0, either = 0;
  for (int i = 0; i < samples; ++i) {
    const Vec3 p = randomPoint(rng, box);
    const bool a = inA(p), b = inB(p);
    both += a && b;
    either += a || b;
  }
  return either ? double(both) / double(either) : 1.0;
}

/// Volumetric IoU of two bounded trees, on 400 000 random points of their
/// joint bounds.
inline double treeIou(const CsgTree& a, const CsgTree& b) {
  Aabb box = a.bounds();
  const Aabb bb = b.bounds();
  box.min = box.min.cwiseMin(bb.min);
  box.max = box.max.cwiseMax(bb.max);
  return sampledIou(
      box, [&](const Vec3& p) { return a.contains(p); },
      [&](const Vec3& p) { return b.contains(p); }, 400000, 7);
}

/// A random, valid primitive of the given type: centre in [-2,2]^3, random
/// orientation, sizes in [0.5, 2] (the torus keeps minor < major).
inline Primitive randomPrimitive(PrimitiveType type, Rng& rng) {
  const Vec3 c(uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2));
  switch (type) {
    case PrimitiveType::HalfSpace:
      return HalfSpace{randomUnit(rng), uniform(rng, -1, 1)};
    case PrimitiveType::Box:
      return Box{c, randomRotation(rng),
                 Vec3(uniform(rng, 0.5, 2), uniform(rng, 0.5, 2), uniform(rng, 0.5, 2))};
    case PrimitiveType::Cylinder:
      return Cylinder{c, randomUnit(rng), uniform(rng, 0.5, 2), uniform(rng, 0.5, 2)};
    case PrimitiveType::Cone:
      return Cone{c, randomUnit(rng), uniform(rng, 0.0, 2), uniform(rng, 0.0, 2),
                  uniform(rng, 0.5, 2)};
    case PrimitiveType::Sphere:
      return Sphere{c, uniform(rng, 0.5, 2)};
    case PrimitiveType::Torus: {
      const double major = uniform(rng, 1.0, 2.0);
      return Torus{c, randomUnit(rng), major, uniform(rng, 0.2, 0.9) * major};
    }
  }
  return {};
}

/// Every primitive type, in enum order.
inline std::vector<PrimitiveType> allPrimitiveTypes() {
  return {PrimitiveType::HalfSpace, PrimitiveType::Box,    PrimitiveType::Cylinder,
          PrimitiveType::Cone,      PrimitiveType::Sphere, PrimitiveType::Torus};
}

/// A random bounded primitive (any type but the half-space).
inline Primitive randomBoundedPrimitive(Rng& rng) {
  const auto types = allPrimitiveTypes();
  const std::size_t k = std::uniform_int_distribution<std::size_t>(1, types.size() - 1)(rng);
  return randomPrimitive(types[k], rng);
}

/// A random tree with `leaves` bounded leaves (named "p0", "p1", ...) joined
/// by random unions, intersections, differences and complements.
inline CsgTree randomTree(Rng& rng, int leaves) {
  std::vector<CsgTree> pool;
  for (int i = 0; i < leaves; ++i) {
    std::string name = "p";
    name += std::to_string(i);
    pool.push_back(CsgTree::leaf(randomBoundedPrimitive(rng), name));
  }
  while (pool.size() > 1) {
    const std::size_t n =
        std::min<std::size_t>(pool.size(), std::uniform_int_distribution<std::size_t>(2, 3)(rng));
    std::vector<CsgTree> operands(pool.end() - static_cast<std::ptrdiff_t>(n), pool.end());
    pool.resize(pool.size() - n);
    CsgTree t;
    switch (std::uniform_int_distribution<int>(0, 3)(rng)) {
      case 0:
        t = CsgTree::unite(operands);
        break;
      case 1:
        t = CsgTree::intersect(operands);
        break;
      case 2:
        t = CsgTree::subtract(operands);
        break;
      default:
        operands.back() = CsgTree::complement(operands.back());
        t = CsgTree::intersect(operands);
    }
    pool.insert(pool.begin(), t);
  }
  return pool.front();
}

/// Point-in-solid test written independently of the distance fields: plain
/// inequalities on the shape parameters (true on the boundary).
inline bool insideReference(const Primitive& prim, const Vec3& p) {
  // Distance from the axis through c with unit direction a, via the cross product.
  auto rhoOf = [](const Vec3& p, const Vec3& c, const Vec3& a) { return (p - c).cross(a).norm(); };
  if (const auto* s = prim.as<HalfSpace>()) return s->normal.dot(p) <= s->offset;
  if (const auto* s = prim.as<Box>()) {
    for (int i = 0; i < 3; ++i) {
      if (std::abs(s->axes.col(i).dot(p - s->center)) > s->halfSize[i]) return false;
    }
    return true;
  }
  if (const auto* s = prim.as<Cylinder>()) {
    return std::abs((p - s->center).dot(s->axis)) <= 0.5 * s->height &&
           rhoOf(p, s->center, s->axis) <= s->radius;
  }
  if (const auto* s = prim.as<Cone>()) {
    const double t = (p - s->center).dot(s->axis) / s->height + 0.5;  // 0 bottom, 1 top
    if (t < 0.0 || t > 1.0) return false;
    return rhoOf(p, s->center, s->axis) <= (1.0 - t) * s->radiusBottom + t * s->radiusTop;
  }
  if (const auto* s = prim.as<Sphere>())
    return (p - s->center).squaredNorm() <= s->radius * s->radius;
  if (const auto* s = prim.as<Torus>()) {
    const double z = (p - s->center).dot(s->axis);
    const double q = rhoOf(p, s->center, s->axis) - s->majorRadius;
    return q * q + z * z <= s->minorRadius * s->minorRadius;
  }
  return false;
}

/// Points on a primitive's surface from its parametrisation, with `cover`: an
/// upper bound on the distance from any surface point to the nearest sample.
struct SurfaceSamples {
  std::vector<Vec3> points;
  double cover = 0.0;
};

namespace detail {

// n+1 values evenly spaced from a to b (both included).
inline std::vector<double> linspace(double a, double b, int n) {
  std::vector<double> v(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) v[static_cast<std::size_t>(i)] = a + (b - a) * i / n;
  return v;
}

inline int stepsFor(double length, double step) {
  return std::max(2, static_cast<int>(std::ceil(length / step)));
}

// Samples a disc of radius r centred at c in the plane spanned by u and v;
// returns the covering radius.
inline double sampleDisc(std::vector<Vec3>& out, const Vec3& c, const Vec3& u, const Vec3& v,
                         double r, double step) {
  if (r <= 0.0) {
    out.push_back(c);
    return 0.0;
  }
  const int nr = stepsFor(r, step);
  const int na = stepsFor(2.0 * std::numbers::pi * r, step);
  for (double rr : linspace(0.0, r, nr)) {
    for (int j = 0; j < na; ++j) {
      const double a = 2.0 * std::numbers::pi * j / na;
      out.push_back(c + rr * (std::cos(a) * u + std::sin(a) * v));
    }
  }
  return 0.5 * std::hypot(r / nr, 2.0 * std::numbers::pi * r / na);
}

}  // namespace detail

/// Samples the surface of `prim` with a spacing of about `step` (scan units).
/// A half-space is sampled on the square of side 10 centred at the foot of the
/// origin on its plane.
inline SurfaceSamples sampleSurface(const Primitive& prim, double step) {
  using detail::linspace;
  using detail::stepsFor;
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  SurfaceSamples s;
  if (const auto* h = prim.as<HalfSpace>()) {
    const Mat3 f = frameFromAxis(h->normal);
    const Vec3 foot = h->offset * h->normal;
    const int n = stepsFor(10.0, step);
    for (double a : linspace(-5, 5, n)) {
      for (double b : linspace(-5, 5, n)) s.points.push_back(foot + a * f.col(0) + b * f.col(1));
    }
    s.cover = 0.5 * std::hypot(10.0 / n, 10.0 / n);
  } else if (const auto* b = prim.as<Box>()) {
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      const int ni = stepsFor(2 * b->halfSize[i], step), nj = stepsFor(2 * b->halfSize[j], step);
      for (double side : {-1.0, 1.0}) {
        for (double x : linspace(-b->halfSize[i], b->halfSize[i], ni)) {
          for (double y : linspace(-b->halfSize[j], b->halfSize[j], nj)) {
            s.points.push_back(b->center + side * b->halfSize[k] * b->axes.col(k) +
                               x * b->axes.col(i) + y * b->axes.col(j));
          }
        }
        s.cover =
            std::max(s.cover, 0.5 * std::hypot(2 * b->halfSize[i] / ni, 2 * b->halfSize[j] / nj));
      }
    }
  } else if (const auto* c = prim.as<Cylinder>()) {
    const Mat3 f = frameFromAxis(c->axis);
    const int na = stepsFor(kTwoPi * c->radius, step), nz = stepsFor(c->height, step);
    for (double z : linspace(-0.5 * c->height, 0.5 * c->height, nz)) {
      for (int j = 0; j < na; ++j) {
        const double a = kTwoPi * j / na;
        s.points.push_back(c->center + z * c->axis +
                           c->radius * (std::cos(a) * f.col(0) + std::sin(a) * f.col(1)));
      }
    }
    s.cover = 0.5 * std::hypot(kTwoPi * c->radius / na, c->height / nz);
    for (double side : {-1.0, 1.0}) {
      s.cover = std::max(s.cover,
                         detail::sampleDisc(s.points, c->center + side * 0.5 * c->height * c->axis,
                                            f.col(0), f.col(1), c->radius, step));
    }
  } else if (const auto* c = prim.as<Cone>()) {
    const Mat3 f = frameFromAxis(c->axis);
    const double rmax = std::max(c->radiusBottom, c->radiusTop);
    const double slant = std::hypot(c->radiusTop - c->radiusBottom, c->height);
    const int na = stepsFor(kTwoPi * rmax, step), nt = stepsFor(slant, step);
    for (double t : linspace(0.0, 1.0, nt)) {
      const double r = (1 - t) * c->radiusBottom + t * c->radiusTop;
      const Vec3 base = c->center + (t - 0.5) * c->height * c->axis;
      for (int j = 0; j < na; ++j) {
        const double a = kTwoPi * j / na;
        s.points.push_back(base + r * (std::cos(a) * f.col(0) + std::sin(a) * f.col(1)));
      }
    }
    s.cover = 0.5 * std::hypot(kTwoPi * rmax / na, slant / nt);
    s.cover = std::max(s.cover, detail::sampleDisc(s.points, c->center - 0.5 * c->height * c->axis,
                                                   f.col(0), f.col(1), c->radiusBottom, step));
    s.cover = std::max(s.cover, detail::sampleDisc(s.points, c->center + 0.5 * c->height * c->axis,
                                                   f.col(0), f.col(1), c->radiusTop, step));
  } else if (const auto* sp = prim.as<Sphere>()) {
    const int nt = stepsFor(std::numbers::pi * sp->radius, step);
    const int na = stepsFor(kTwoPi * sp->radius, step);
    for (double t : linspace(0.0, std::numbers::pi, nt)) {
      for (int j = 0; j < na; ++j) {
        const double a = kTwoPi * j / na;
        s.points.push_back(sp->center + sp->radius * Vec3(std::sin(t) * std::cos(a),
                                                          std::sin(t) * std::sin(a), std::cos(t)));
      }
    }
    s.cover = 0.5 * std::hypot(std::numbers::pi * sp->radius / nt, kTwoPi * sp->radius / na);
  } else if (const auto* to = prim.as<Torus>()) {
    const Mat3 f = frameFromAxis(to->axis);
    const double R = to->majorRadius, r = to->minorRadius;
    const int na = stepsFor(kTwoPi * (R + r), step), nb = stepsFor(kTwoPi * r, step);
    for (int i = 0; i < na; ++i) {
      const double a = kTwoPi * i / na;
      const Vec3 radial = std::cos(a) * f.col(0) + std::sin(a) * f.col(1);
      for (int j = 0; j < nb; ++j) {
        const double b = kTwoPi * j / nb;
        s.points.push_back(to->center + (R + r * std::cos(b)) * radial +
                           r * std::sin(b) * to->axis);
      }
    }
    s.cover = 0.5 * std::hypot(kTwoPi * (R + r) / na, kTwoPi * r / nb);
  }
  return s;
}

/// Distance from p to the nearest sample.
inline double nearestSampleDistance(const std::vector<Vec3>& samples, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Vec3& q : samples) best = std::min(best, (q - p).squaredNorm());
  return std::sqrt(best);
}

/// Central finite-difference gradient of fn at p with step h.
inline Vec3 numericGradient(const std::function<double(const Vec3&)>& fn, const Vec3& p, double h) {
  Vec3 g;
  for (int i = 0; i < 3; ++i) {
    const Vec3 e = h * Vec3::Unit(i);
    g[i] = (fn(p + e) - fn(p - e)) / (2.0 * h);
  }
  return g;
}

/// True when fn is smooth enough around p for a finite-difference gradient to
/// be meaningful: two step sizes give the same answer (p is not within about
/// `h` of a crease or of the medial axis).
inline bool isSmoothAt(const std::function<double(const Vec3&)>& fn, const Vec3& p, double h) {
  return (numericGradient(fn, p, h) - numericGradient(fn, p, 0.01 * h)).norm() < 1e-4;
}

/// Samples `samples` random points (seeded) in the union of both trees' bounds
/// grown by 10% (in `fallback` when that is unbounded) and checks that the
/// trees classify them alike. Points within 1e-9 of either surface are not
/// counted; at least 90% of the points must be counted.
inline ::testing::AssertionResult treesEquivalent(const CsgTree& a, const CsgTree& b, int samples,
                                                  std::uint64_t seed,
                                                  const Aabb& fallback = Aabb{Vec3::Constant(-10),
                                                                              Vec3::Constant(10)}) {
  Aabb box = a.bounds();
  box.extend(b.bounds());
  if (!box.isBounded()) {
    box = fallback;
  } else {
    box = box.grown(0.1 * box.diagonal());
  }
  Rng rng(seed);
  int counted = 0, inA = 0, inB = 0;
  for (int i = 0; i < samples; ++i) {
    const Vec3 p = randomPoint(rng, box);
    const double fa = a.value(p), fb = b.value(p);
    if (std::abs(fa) < 1e-9 || std::abs(fb) < 1e-9) continue;
    ++counted;
    inA += fa > 0.0;
    inB += fb > 0.0;
    if ((fa > 0.0) != (fb > 0.0)) {
      return ::testing::AssertionFailure()
             << "trees differ at " << str(p) << ": values " << fa << " and " << fb;
    }
  }
  if (counted < 0.9 * samples) {
    return ::testing::AssertionFailure()
           << "only " << counted << " of " << samples << " points were away from the surfaces";
  }
  return ::testing::AssertionSuccess() << counted << " points agree (" << inA << " inside)";
}

/// Expects two trees to describe the same solid (see treesEquivalent);
/// failures are reported at the caller's line.
inline void expectTreesEquivalent(const CsgTree& a, const CsgTree& b, int samples = 4000,
                                  std::uint64_t seed = 1,
                                  std::source_location loc = std::source_location::current()) {
  ::testing::ScopedTrace trace(loc.file_name(), static_cast<int>(loc.line()),
                               "expectTreesEquivalent");
  EXPECT_TRUE(treesEquivalent(a, b, samples, seed));
}

/// A plate 60 x 40 and 1.2 thick with six square through-holes of side 6,
/// turned 40 degrees about z: walls narrower than a neighbourhood of a
/// 50 000-point sample is tall, at no angle the plate's faces share (the
/// diamond holes of InverseCSG's part 109, on which raw scans lost them).
inline CsgTree thinPlateWithTurnedHoles() {
  std::vector<CsgTree> parts{
      CsgTree::leaf(Box{Vec3(0, 0, 0.6), Mat3::Identity(), Vec3(30, 20, 0.6)}, "plate")};
  const double a = 40.0 * std::numbers::pi / 180.0;
  Mat3 turned;
  turned << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  for (double x : {-16.0, 0.0, 16.0}) {
    for (double y : {-8.0, 8.0}) {
      parts.push_back(CsgTree::leaf(Box{Vec3(x, y, 0.6), turned, Vec3(3, 3, 1)},
                                    "hole_" + std::to_string(parts.size())));
    }
  }
  return CsgTree::subtract(parts);
}

}  // namespace csgvox::test
