// Tests for core/sardf.h and SardfOperations: the SARDF union and
// intersection against the paper's quadratic roots and hand-computed values,
// their agreement with min/max (sign everywhere, value outside the blending
// band), continuity and C¹ continuity across every branch boundary, the
// documented gradient jump on the zone boundary arcs, derivatives against
// finite differences, and batched tree evaluation bit for bit.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/csg_tree.h"
#include "core/sardf.h"
#include "core/set_operations.h"
#include "core/tree_program.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::Rng;

constexpr double kSqrt2 = std::numbers::sqrt2;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Largest difference from min/max: (1 − 1/√2)·R.
constexpr double kMaxDeviation = 1.0 - 1.0 / kSqrt2;

double sq(double x) { return x * x; }

// The union as the paper writes it (§3.2, the roots of a·c² + b·c + c0 = 0
// with its coefficients), with the signs of the negative case and the test of
// its zone corrected; written on f1, f2 directly, without ordering them.
double referenceUnite(double f1, double f2, double r) {
  if (f1 <= 0 && f2 >= 0) return f2;
  if (f1 >= 0 && f2 <= 0) return f1;
  const double m = std::max(f1, f2);
  const auto band = [&] {
    if (!(std::abs(f1 - f2) < r)) return m;
    const double a = 2, b = -2 * f1 - 2 * f2 - 4 * r,
                 c = f1 * f1 + f2 * f2 + 2 * f1 * r + 2 * f2 * r + r * r;
    return (-b - std::sqrt(b * b - 4 * a * c)) / (2 * a);
  };
  const double ratio = f2 / f1;
  if (f1 > 0) {
    const bool e1 =
        f1 < r || f2 < r || (f1 < 2 * r && f2 < 2 * r && sq(f1 - r) + sq(f2 - r) < r * r);
    if (!e1) return band();
    if (!(0.5 < ratio && ratio < 2)) return m;
    const double a = 0.25, b = -(f1 + f2), c = f1 * f1 + f2 * f2;
    return (-b - std::sqrt(b * b - 4 * a * c)) / (2 * a);
  }
  const bool e2 =
      f1 > -r || f2 > -r || (f1 > -2 * r && f2 > -2 * r && sq(f1 + 2 * r) + sq(f2 + 2 * r) > r * r);
  if (!e2) return band();
  if (!(0.5 < ratio && ratio < 2)) return m;
  const double a = 7, b = -4 * (f1 + f2), c = f1 * f1 + f2 * f2;
  return (-b - std::sqrt(b * b - 4 * a * c)) / (2 * a);
}

int signOf(double x) { return (x > 0) - (x < 0); }

// ---------------------------------------------------------------------------
// Values.

TEST(Sardf, HandComputedValuesOnTheDiagonal) {
  const double r = 0.7;
  const double zoneIPositive = 2 * (2 - kSqrt2);  // c = 2(2 − √2)·t
  const double zoneINegative = (4 + kSqrt2) / 7;  // c = (4 + √2)/7·t
  const double bandLift = kMaxDeviation * r;      // c = t + (1 − 1/√2)·R
  // Both > 0: zone I near the origin and inside the zone circle, zone II far.
  for (const double t : {1e-9, 0.1 * r, 0.9 * r, 1.5 * r, 1.7 * r}) {
    EXPECT_NEAR(sardfUnite(t, t, r).f, zoneIPositive * t, 4e-15 * t) << t;
  }
  for (const double t : {1.8 * r, 3 * r, 100 * r}) {
    EXPECT_NEAR(sardfUnite(t, t, r).f, t + bandLift, 1e-14 * t) << t;
  }
  // Both < 0: zone I while t > −(2 − 1/√2)·R ≈ −1.29 R, zone II beyond.
  for (const double t : {-1e-9, -0.5 * r, -1.2 * r, -1.29 * r}) {
    EXPECT_NEAR(sardfUnite(t, t, r).f, zoneINegative * t, 4e-15 * -t) << t;
  }
  for (const double t : {-1.3 * r, -3 * r, -100 * r}) {
    EXPECT_NEAR(sardfUnite(t, t, r).f, t + bandLift, 1e-14 * -t) << t;
  }
  // The derivatives along the diagonal: half the slope each.
  EXPECT_NEAR(sardfUnite(0.5 * r, 0.5 * r, r).d1, zoneIPositive / 2, 1e-15);
  EXPECT_NEAR(sardfUnite(3 * r, 3 * r, r).d2, 0.5, 1e-15);
  EXPECT_NEAR(sardfUnite(-0.5 * r, -0.5 * r, r).d1, zoneINegative / 2, 1e-15);
  // Intersection mirrors union.
  EXPECT_NEAR(sardfIntersect(0.5 * r, 0.5 * r, r).f, zoneINegative * 0.5 * r, 1e-15);
  EXPECT_NEAR(sardfIntersect(3 * r, 3 * r, r).f, 3 * r - bandLift, 1e-14);
  EXPECT_NEAR(sardfIntersect(-0.5 * r, -0.5 * r, r).f, -zoneIPositive * 0.5 * r, 1e-15);
}

TEST(Sardf, HandComputedValuesOffTheDiagonal) {
  // Zone I, both > 0: 2(1 + 0.8) − 2·sqrt(1.6).
  EXPECT_NEAR(sardfUnite(1.0, 0.8, 10.0).f, 3.6 - 2 * std::sqrt(1.6), 1e-15);
  // Zone II: ((3 + 2.5 + 2) − sqrt(2 − 0.25)) / 2 with R = 1.
  EXPECT_NEAR(sardfUnite(3.0, 2.5, 1.0).f, (7.5 - std::sqrt(1.75)) / 2, 1e-15);
  EXPECT_NEAR(sardfUnite(-3.0, -2.5, 1.0).f, (-3.5 - std::sqrt(1.75)) / 2, 1e-15);
  // Zone I, both < 0: (4(−1.8) − sqrt(32·0.8 − 12(1 + 0.64))) / 14.
  EXPECT_NEAR(sardfUnite(-1.0, -0.8, 10.0).f, (-7.2 - std::sqrt(25.6 - 19.68)) / 14, 1e-15);
  // On the wedge and band lines the value is the max exactly.
  EXPECT_EQ(sardfUnite(1.0, 0.5, 10.0).f, 1.0);
  EXPECT_EQ(sardfUnite(-1.0, -2.0, 10.0).f, -1.0);
  EXPECT_EQ(sardfUnite(5.0, 4.0, 1.0).f, 5.0);
}

TEST(Sardf, MatchesThePapersQuadraticRoots) {
  Rng rng(1);
  const double r = 1.3;
  int blended = 0;
  for (int i = 0; i < 200000; ++i) {
    const double scale = i % 4 == 0 ? 0.05 : 6.0;
    const double f1 = test::uniform(rng, -scale, scale), f2 = test::uniform(rng, -scale, scale);
    const double expected = referenceUnite(f1, f2, r);
    const double got = sardfUnite(f1, f2, r).f;
    ASSERT_NEAR(got, expected, 1e-12 * (r + std::abs(f1) + std::abs(f2))) << f1 << ", " << f2;
    blended += got != std::max(f1, f2);
  }
  EXPECT_GT(blended, 20000);  // the comparison covers the arcs, not just max
}

TEST(Sardf, EqualsMinMaxOutsideTheBlendingBand) {
  Rng rng(2);
  const double r = 0.4;
  for (int i = 0; i < 100000; ++i) {
    const double f1 = test::uniform(rng, -10, 10);
    const double gap = test::uniform(rng, r, 10);
    const double f2 = i % 2 ? f1 + gap : f1 - gap;  // |f1 − f2| >= R
    ASSERT_EQ(sardfUnite(f1, f2, r).f, std::max(f1, f2)) << f1 << ", " << f2;
    ASSERT_EQ(sardfIntersect(f1, f2, r).f, std::min(f1, f2)) << f1 << ", " << f2;
  }
  // Near the origin the blend stays inside the wedge 1/2 < f2/f1 < 2.
  for (const double s : {1e-6, 0.01, 0.1}) {
    for (const double k : {2.0, 2.5, 10.0}) {
      EXPECT_EQ(sardfUnite(s, k * s, r).f, k * s);
      EXPECT_EQ(sardfUnite(k * s, s, r).f, k * s);
      EXPECT_EQ(sardfUnite(-s, -k * s, r).f, -s);
      EXPECT_EQ(sardfIntersect(s, k * s, r).f, s);
      EXPECT_EQ(sardfIntersect(-s, -k * s, r).f, -k * s);
    }
    EXPECT_GT(sardfUnite(s, 1.9 * s, r).f, 1.9 * s);
    EXPECT_GT(sardfUnite(-s, -1.9 * s, r).f, -s);
  }
  // Opposite signs: the non-negative operand, including zeros.
  EXPECT_EQ(sardfUnite(0.0, -0.1, r).f, 0.0);
  EXPECT_EQ(sardfUnite(-0.1, 0.0, r).f, 0.0);
  EXPECT_EQ(sardfUnite(0.3, -0.3, r).f, 0.3);
  EXPECT_EQ(sardfIntersect(0.0, 0.1, r).f, 0.0);
  EXPECT_EQ(sardfIntersect(0.3, -0.3, r).f, -0.3);
}

TEST(Sardf, SignOfMinMaxAndBoundedDeviationOnADenseGrid) {
  // Grids of three scales around the origin; index 400 is exactly 0, so the
  // axes and the origin are on the grid.
  for (const double r : {0.01, 1.0, 50.0}) {
    for (const double step : {1e-3 * r, 1e-2 * r}) {
      std::size_t blended = 0;
      for (int i = 0; i <= 800; ++i) {
        for (int j = 0; j <= 800; ++j) {
          const double f1 = (i - 400) * step, f2 = (j - 400) * step;
          const double hi = std::max(f1, f2), lo = std::min(f1, f2);
          const double u = sardfUnite(f1, f2, r).f, n = sardfIntersect(f1, f2, r).f;
          ASSERT_EQ(signOf(u), signOf(hi)) << f1 << ", " << f2 << " R " << r;
          ASSERT_EQ(signOf(n), signOf(lo)) << f1 << ", " << f2 << " R " << r;
          ASSERT_GE(u, hi);
          ASSERT_LE(n, lo);
          ASSERT_LE(u - hi, kMaxDeviation * r * (1 + 1e-12));
          ASSERT_LE(lo - n, kMaxDeviation * r * (1 + 1e-12));
          blended += u != hi;
        }
      }
      EXPECT_GT(blended, 10000u);
    }
  }
  // Extreme magnitudes keep the sign and stay finite.
  for (const double s : {1e-310, 1e-300, 1e-160, 1e150, 1e300}) {
    for (const double k : {1.0, 1.5, -1.0}) {
      for (const double sign : {1.0, -1.0}) {
        const double f1 = sign * s, f2 = sign * k * s;
        const SardfResult u = sardfUnite(f1, f2, 1.0);
        EXPECT_EQ(signOf(u.f), signOf(std::max(f1, f2))) << f1 << ", " << f2;
        EXPECT_TRUE(std::isfinite(u.f) && std::isfinite(u.d1) && std::isfinite(u.d2))
            << f1 << ", " << f2;
      }
    }
  }
  // The smallest negative values stay negative (the zone I factor is ~0.77).
  const double tiny = std::numeric_limits<double>::denorm_min();
  EXPECT_LT(sardfUnite(-tiny, -tiny, 1.0).f, 0.0);
  EXPECT_GT(sardfIntersect(tiny, tiny, 1.0).f, 0.0);
  // Infinite operands (the value of an empty tree) act as with max.
  EXPECT_EQ(sardfUnite(-kInf, -0.5, 1.0).f, -0.5);
  EXPECT_EQ(sardfUnite(-kInf, -5.0, 1.0).f, -5.0);
  EXPECT_EQ(sardfUnite(-kInf, 2.0, 1.0).f, 2.0);
  EXPECT_EQ(sardfUnite(kInf, 2.0, 1.0).f, kInf);
  EXPECT_EQ(sardfIntersect(kInf, 0.5, 1.0).f, 0.5);
}

TEST(Sardf, SymmetricInItsOperandsAndIntersectionIsTheDualOfUnion) {
  Rng rng(3);
  for (int i = 0; i < 100000; ++i) {
    const double s = std::pow(10.0, test::uniform(rng, -3, 1));
    double f1 = test::uniform(rng, -4, 4) * s, f2 = test::uniform(rng, -4, 4) * s;
    if (i % 10 == 0) f2 = f1;
    if (i % 10 == 1) f2 = 0.5 * f1;
    if (i % 10 == 2) f2 = f1 - 1.0;
    const double r = 1.0;
    const SardfResult a = sardfUnite(f1, f2, r), b = sardfUnite(f2, f1, r);
    ASSERT_EQ(a.f, b.f) << f1 << ", " << f2;
    if (f1 == 0 && f2 == 0) continue;  // the corner: the first operand's derivative
    if (f1 != f2) {
      ASSERT_EQ(a.d1, b.d2);
      ASSERT_EQ(a.d2, b.d1);
    } else {
      ASSERT_NEAR(a.d1, a.d2, 1e-15);
    }
    const SardfResult n = sardfIntersect(f1, f2, r), m = sardfUnite(-f1, -f2, r);
    ASSERT_EQ(n.f, -m.f);
    ASSERT_EQ(n.d1, m.d1);
    ASSERT_EQ(n.d2, m.d2);
    ASSERT_EQ(sardfIntersect(f2, f1, r).f, n.f);
  }
}

TEST(Sardf, ValueFormsAreBitForBitTheValues) {
  Rng rng(4);
  const SardfOperations ops(0.8);
  const SardfValues values = ops.values();
  for (int i = 0; i < 100000; ++i) {
    const double s = std::pow(10.0, test::uniform(rng, -4, 2));
    FieldValue a{test::uniform(rng, -3, 3) * s, test::randomUnit(rng)};
    FieldValue b{test::uniform(rng, -3, 3) * s, test::randomUnit(rng)};
    if (i % 10 == 0) b.f = a.f;
    if (i % 10 == 1) a.f = 0.0;
    if (i % 10 == 2) b.f = -1e200;
    ASSERT_EQ(sardfUniteValue(a.f, b.f, 0.8), sardfUnite(a.f, b.f, 0.8).f);
    ASSERT_EQ(sardfIntersectValue(a.f, b.f, 0.8), sardfIntersect(a.f, b.f, 0.8).f);
    ASSERT_EQ(values.unite(a.f, b.f), ops.unite(a, b).f);
    ASSERT_EQ(values.intersect(a.f, b.f), ops.intersect(a, b).f);
  }
}

// ---------------------------------------------------------------------------
// Continuity and C¹ continuity across the branch boundaries.

using Field2 = std::function<double(double, double)>;

// Second-order one-sided derivative of fn at (p1, p2) along (w1, w2).
double oneSided(const Field2& fn, double p1, double p2, double w1, double w2, double h) {
  const double f0 = fn(p1, p2), f1 = fn(p1 + h * w1, p2 + h * w2);
  const double f2 = fn(p1 + 2 * h * w1, p2 + 2 * h * w2);
  return (-3 * f0 + 4 * f1 - f2) / (2 * h);
}

// A point on a boundary curve and the unit normal across it.
struct Crossing {
  double p1, p2, n1, n2;
};

// The jump of the one-sided derivatives across the curve, along the normal
// and along a direction 45° from it, and the jump of the value itself.
struct Jumps {
  double value, normal, skew;
};

// `scale`: the length over which fn's second derivatives stay bounded.
Jumps jumpsAt(const Field2& fn, const Crossing& c, double scale) {
  const double h = 1e-4 * scale, eps = 1e-12 * scale;
  // The skew direction (n + t)/√2, t the tangent.
  const double s1 = (c.n1 - c.n2) / kSqrt2, s2 = (c.n2 + c.n1) / kSqrt2;
  Jumps j;
  j.value =
      std::abs(fn(c.p1 + eps * c.n1, c.p2 + eps * c.n2) - fn(c.p1 - eps * c.n1, c.p2 - eps * c.n2));
  j.normal =
      std::abs(oneSided(fn, c.p1, c.p2, c.n1, c.n2, h) + oneSided(fn, c.p1, c.p2, -c.n1, -c.n2, h));
  j.skew = std::abs(oneSided(fn, c.p1, c.p2, s1, s2, h) + oneSided(fn, c.p1, c.p2, -s1, -s2, h));
  return j;
}

// Points along a segment from (a1, a2) to (b1, b2), with the normal (n1, n2).
std::vector<Crossing> alongSegment(double a1, double a2, double b1, double b2, int count) {
  const double len = std::hypot(b1 - a1, b2 - a2);
  const double n1 = -(b2 - a2) / len, n2 = (b1 - a1) / len;
  std::vector<Crossing> out;
  for (int i = 0; i <= count; ++i) {
    const double t = static_cast<double>(i) / count;
    out.push_back({a1 + t * (b1 - a1), a2 + t * (b2 - a2), n1, n2});
  }
  return out;
}

// Points on the quarter arc of centre (c, c) and radius r, angles in (lo, hi).
std::vector<Crossing> alongArc(double c, double r, double lo, double hi, int count) {
  std::vector<Crossing> out;
  for (int i = 0; i <= count; ++i) {
    const double a = lo + (hi - lo) * i / count;
    out.push_back({c + r * std::cos(a), c + r * std::sin(a), std::cos(a), std::sin(a)});
  }
  return out;
}

// Every boundary between branches of the union with radius r, except the
// zone arcs: the diagonal, the wedge lines, the band lines, the straight parts
// of the zone boundaries and the axes.
std::vector<Crossing> smoothUnionBoundaries(double r) {
  std::vector<Crossing> all;
  const auto add = [&](const std::vector<Crossing>& c) {
    all.insert(all.end(), c.begin(), c.end());
  };
  // The diagonal, both signs, without its crossings of the zone arcs.
  add(alongSegment(0.01 * r, 0.01 * r, 1.69 * r, 1.69 * r, 200));
  add(alongSegment(1.725 * r, 1.725 * r, 8 * r, 8 * r, 200));
  add(alongSegment(-0.01 * r, -0.01 * r, -1.28 * r, -1.28 * r, 200));
  add(alongSegment(-1.305 * r, -1.305 * r, -8 * r, -8 * r, 200));
  add(alongSegment(0.02 * r, 0.04 * r, 0.98 * r, 1.96 * r, 200));  // wedge f2 = 2 f1
  add(alongSegment(0.04 * r, 0.02 * r, 1.96 * r, 0.98 * r, 200));  // wedge f2 = f1 / 2
  add(alongSegment(-0.02 * r, -0.04 * r, -0.98 * r, -1.96 * r, 200));
  add(alongSegment(-0.04 * r, -0.02 * r, -1.96 * r, -0.98 * r, 200));
  add(alongSegment(2.02 * r, 1.02 * r, 9 * r, 8 * r, 200));  // band f2 = f1 − R
  add(alongSegment(1.02 * r, 2.02 * r, 8 * r, 9 * r, 200));  // band f2 = f1 + R
  add(alongSegment(-1.02 * r, -2.02 * r, -8 * r, -9 * r, 200));
  add(alongSegment(-2.02 * r, -1.02 * r, -9 * r, -8 * r, 200));
  add(alongSegment(r, 2.02 * r, r, 9 * r, 100));  // zone I edge f1 = R
  add(alongSegment(2.02 * r, r, 9 * r, r, 100));
  add(alongSegment(-r, -2.02 * r, -r, -9 * r, 100));  // zone I edge f1 = −R
  add(alongSegment(-2.02 * r, -r, -9 * r, -r, 100));
  add(alongSegment(-2 * r, -1.5 * r, -2 * r, -1.02 * r, 50));  // f1 = −2R inside the disc
  add(alongSegment(0, 0.01 * r, 0, 9 * r, 200));               // axes
  add(alongSegment(0, -0.01 * r, 0, -9 * r, 200));
  add(alongSegment(0.01 * r, 0, 9 * r, 0, 200));
  add(alongSegment(-0.01 * r, 0, -9 * r, 0, 200));
  return all;
}

TEST(Sardf, ContinuousAndC1AcrossEveryBoundaryButTheZoneArcs) {
  for (const double r : {0.05, 1.0, 20.0}) {
    const Field2 unite = [r](double a, double b) { return sardfUnite(a, b, r).f; };
    const Field2 intersect = [r](double a, double b) { return sardfIntersect(a, b, r).f; };
    for (const Crossing& c : smoothUnionBoundaries(r)) {
      const double norm = std::hypot(c.p1, c.p2);
      for (const bool dual : {false, true}) {
        // The intersection's boundaries are the union's mirrored through the origin.
        const Crossing d = dual ? Crossing{-c.p1, -c.p2, c.n1, c.n2} : c;
        const Jumps j = jumpsAt(dual ? intersect : unite, d, std::min(r, norm));
        ASSERT_LT(j.value, 1e-11 * std::max(r, norm)) << d.p1 << ", " << d.p2 << " R " << r;
        ASSERT_LT(j.normal, 2e-5) << d.p1 << ", " << d.p2 << " R " << r;
        ASSERT_LT(j.skew, 2e-5) << d.p1 << ", " << d.p2 << " R " << r;
      }
    }
  }
}

TEST(Sardf, ZoneArcsAreContinuousWithTheGradientsDirectionButNotItsLength) {
  const double r = 1.0;
  const Field2 unite = [r](double a, double b) { return sardfUnite(a, b, r).f; };
  struct Arc {
    double centre;        // of the arc, on the diagonal
    double inner, outer;  // slopes along the diagonal on the centre's side and beyond
    std::vector<Crossing> points;
  };
  // Union of positive values: the level curve c = 2R, centre (R, R), zone I
  // inside. Negative values: c = −R, centre (−2R, −2R), zone II inside.
  const std::vector<Arc> arcs = {
      {r, 2 * (2 - kSqrt2), 1.0, alongArc(r, r, 0.02, std::numbers::pi / 2 - 0.02, 200)},
      {-2 * r, 1.0, (4 + kSqrt2) / 7, alongArc(-2 * r, r, 0.02, std::numbers::pi / 2 - 0.02, 200)},
  };
  for (const Arc& arc : arcs) {
    for (const Crossing& c : arc.points) {
      const Jumps j = jumpsAt(unite, c, r);
      EXPECT_LT(j.value, 1e-11) << c.p1 << ", " << c.p2;
      // The gradients on both sides are parallel (normal to the shared level curve).
      const double eps = 1e-9;
      const SardfResult in = sardfUnite(c.p1 - eps * c.n1, c.p2 - eps * c.n2, r);
      const SardfResult out = sardfUnite(c.p1 + eps * c.n1, c.p2 + eps * c.n2, r);
      EXPECT_NEAR(in.d1 * out.d2 - in.d2 * out.d1, 0.0, 1e-7) << c.p1 << ", " << c.p2;
      EXPECT_NEAR(in.d1 * c.n2 - in.d2 * c.n1, 0.0, 1e-7) << c.p1 << ", " << c.p2;
    }
    // On the diagonal the slope jumps between the zone I and zone II values
    // (one-sided finite differences along the diagonal).
    const Crossing mid = arc.points[arc.points.size() / 2];
    const double w = 1 / kSqrt2, h = 1e-5;
    const double inner = -oneSided(unite, mid.p1, mid.p2, -w, -w, h) * kSqrt2;
    const double outer = oneSided(unite, mid.p1, mid.p2, w, w, h) * kSqrt2;
    EXPECT_NEAR(inner, arc.inner, 1e-6);
    EXPECT_NEAR(outer, arc.outer, 1e-6);
    EXPECT_GT(jumpsAt(unite, mid, r).normal, 0.08);  // the check sees a C¹ break
  }
  // The origin keeps its corner; so does max anywhere on the diagonal.
  EXPECT_GT(jumpsAt(unite, {0, 0, 1 / kSqrt2, 1 / kSqrt2}, 1e-3).normal, 0.2);
  const Field2 max = [](double a, double b) { return std::max(a, b); };
  EXPECT_GT(jumpsAt(max, {1, 1, 1 / kSqrt2, -1 / kSqrt2}, 1.0).normal, 1.0);
}

// ---------------------------------------------------------------------------
// Derivatives.

TEST(Sardf, DerivativesMatchCentralDifferences) {
  Rng rng(5);
  const double r = 0.6;
  int checked = 0;
  const int total = 40000;
  for (int i = 0; i < total; ++i) {
    const double s = i % 3 == 0 ? 0.1 : 5.0;
    const double f1 = test::uniform(rng, -s, s), f2 = test::uniform(rng, -s, s);
    for (const bool unite : {true, false}) {
      const auto fn = [&](double a, double b) {
        return unite ? sardfUnite(a, b, r).f : sardfIntersect(a, b, r).f;
      };
      const auto gradient = [&](double h) {
        return std::array<double, 2>{(fn(f1 + h, f2) - fn(f1 - h, f2)) / (2 * h),
                                     (fn(f1, f2 + h) - fn(f1, f2 - h)) / (2 * h)};
      };
      const double h = 1e-6 * std::max(1e-2, std::hypot(f1, f2));
      const auto g = gradient(h), coarse = gradient(100 * h);
      // Skip points within ~100 h of a kink (zone arcs, origin).
      if (std::abs(g[0] - coarse[0]) + std::abs(g[1] - coarse[1]) > 1e-5) continue;
      ++checked;
      const SardfResult v = unite ? sardfUnite(f1, f2, r) : sardfIntersect(f1, f2, r);
      ASSERT_NEAR(v.d1, g[0], 1e-6) << f1 << ", " << f2 << (unite ? " union" : " intersection");
      ASSERT_NEAR(v.d2, g[1], 1e-6) << f1 << ", " << f2 << (unite ? " union" : " intersection");
      // Non-decreasing in each operand, with a slope of at most 2(2 − √2).
      ASSERT_GE(v.d1, 0.0);
      ASSERT_GE(v.d2, 0.0);
      ASSERT_LE(v.d1 + v.d2, 2 * (2 - kSqrt2) + 1e-12);
    }
  }
  EXPECT_GT(checked, 2 * total * 99 / 100);
}

// The field of two primitives combined, and its gradient at p.
FieldValue combined(const SetOperations& ops, int operation, const Primitive& a, const Primitive& b,
                    const Vec3& p) {
  FieldValue fa, fb;
  fa.f = a.valueAndGradient(p, fa.gradient);
  fb.f = b.valueAndGradient(p, fb.gradient);
  if (operation == 0) return ops.unite(fa, fb);
  if (operation == 1) return ops.intersect(fa, fb);
  return ops.intersect(fa, FieldValue{-fb.f, -fb.gradient});
}

TEST(SardfOperations, GradientMatchesFiniteDifferences) {
  Rng rng(6);
  int checked = 0, total = 0, blended = 0;
  for (int pair = 0; pair < 30; ++pair) {
    const Primitive a = test::randomBoundedPrimitive(rng), b = test::randomBoundedPrimitive(rng);
    Aabb box = a.bounds();
    box.extend(b.bounds());
    const SardfOperations ops(sardfRadius(box.diagonal()) * (pair % 2 ? 4 : 1));
    for (int operation = 0; operation < 3; ++operation) {
      const auto fn = [&](const Vec3& p) { return combined(ops, operation, a, b, p).f; };
      for (int i = 0; i < 30; ++i) {
        const Vec3 p = test::randomPoint(rng, box);
        ++total;
        if (!test::isSmoothAt(fn, p, 1e-3)) continue;
        ++checked;
        const FieldValue v = combined(ops, operation, a, b, p);
        blended += v.f != combined(minMaxOperations(), operation, a, b, p).f;
        EXPECT_TRUE(test::vecNear(v.gradient, test::numericGradient(fn, p, 1e-6), 1e-5))
            << "operation " << operation << " at " << test::str(p);
      }
    }
  }
  EXPECT_GE(checked, total * 9 / 10);
  EXPECT_GT(blended, total / 20);
}

// ---------------------------------------------------------------------------
// SardfOperations and trees.

TEST(SardfOperations, RadiusKindAndName) {
  const SardfOperations ops(0.25);
  EXPECT_EQ(ops.radius(), 0.25);
  EXPECT_EQ(ops.values().radius, 0.25);
  EXPECT_EQ(ops.kind(), SetOperationKind::Sardf);
  EXPECT_EQ(ops.name(), "sardf");
  EXPECT_EQ(sardfRadius(10.0), 10.0 * kSardfRadiusFraction);
  for (const double bad : {0.0, -1.0, kInf, std::numeric_limits<double>::quiet_NaN()}) {
    EXPECT_THROW(SardfOperations{bad}, std::invalid_argument) << bad;
  }
  EXPECT_THROW(setOperations(SetOperationKind::Sardf), std::invalid_argument);
  // The kind alone carries no radius.
  const CsgTree tree = CsgTree::leaf(Sphere{Vec3::Zero(), 1.0});
  std::vector<Vec3> points(3, Vec3::Zero());
  std::vector<double> out(3);
  EXPECT_THROW(tree.values(points, out, SetOperationKind::Sardf), std::invalid_argument);
  EXPECT_THROW(TreeProgram(tree).values(points, out, SetOperationKind::Sardf),
               std::invalid_argument);
  std::vector<double> tooShort(2);
  EXPECT_THROW(tree.values(points, tooShort, ops), std::invalid_argument);
}

TEST(SardfOperations, DifferenceIsIntersectionWithTheComplement) {
  Rng rng(7);
  const Primitive a = Sphere{Vec3::Zero(), 1.0};
  const Primitive b = Box{Vec3(0.8, 0, 0), Mat3::Identity(), Vec3(0.5, 0.5, 0.5)};
  const CsgTree ta = CsgTree::leaf(a), tb = CsgTree::leaf(b);
  const CsgTree diff = CsgTree::subtract({ta, tb});
  const CsgTree viaComplement = CsgTree::intersect({ta, CsgTree::complement(tb)});
  const SardfOperations ops(0.5);
  int blended = 0;
  // Mostly inside the sphere, where the operands can have the same sign.
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p = test::randomPoint(rng, Aabb{Vec3::Constant(-1.1), Vec3::Constant(1.1)});
    FieldValue fa, fb;
    fa.f = a.valueAndGradient(p, fa.gradient);
    fb.f = b.valueAndGradient(p, fb.gradient);
    const FieldValue expected = ops.intersect(fa, FieldValue{-fb.f, -fb.gradient});
    const FieldValue got = diff.evaluate(p, ops);
    ASSERT_EQ(got.f, expected.f);
    test::expectNear(got.gradient, expected.gradient, 0.0);
    const FieldValue other = viaComplement.evaluate(p, ops);
    ASSERT_EQ(other.f, got.f);
    test::expectNear(other.gradient, got.gradient, 0.0);
    ASSERT_EQ(diff.value(p, ops), got.f);
    blended += got.f != diff.value(p);
  }
  EXPECT_GT(blended, 300);
}

TEST(SardfOperations, TreesKeepTheirSolidAndStayNearMinMax) {
  Rng rng(8);
  int inside = 0, outside = 0;
  for (int t = 0; t < 30; ++t) {
    const CsgTree tree = test::randomTree(rng, 2 + t % 6);
    Aabb box = tree.leaves().front()->primitive.bounds().grown(1.0);
    for (const Node* leaf : tree.leaves()) box.extend(leaf->primitive.bounds());
    const SardfOperations ops(sardfRadius(box.diagonal()));
    // Each of the n = leaves − 1 binary operations moves the value by at most
    // (1 − 1/√2)·R and amplifies earlier differences by at most 2(2 − √2) < 1.2.
    const double n = static_cast<double>(tree.primitiveCount() - 1);
    const double drift = kMaxDeviation * ops.radius() * n * std::pow(1.2, n) + 1e-12;
    for (int i = 0; i < 500; ++i) {
      const Vec3 p = test::randomPoint(rng, box);
      const double m = tree.value(p), s = tree.value(p, ops);
      ASSERT_EQ(signOf(s), signOf(m)) << "tree " << t << " at " << test::str(p);
      ASSERT_LE(std::abs(s - m), drift);
      (m > 0 ? inside : outside)++;
    }
  }
  EXPECT_GT(inside, 500);
  EXPECT_GT(outside, 500);
}

TEST(SardfOperations, BatchedValuesAreBitForBitTheValuesAndTheEvaluatedValues) {
  Rng rng(9);
  std::size_t blended = 0;
  for (int t = 0; t < 40; ++t) {
    const CsgTree tree = test::randomTree(rng, 1 + t % 9);
    const SardfOperations ops(t % 2 ? 0.05 : 0.5);
    // Sizes around the internal chunk length, and an empty batch.
    for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{255}, std::size_t{256},
                                std::size_t{257}, std::size_t{1500}}) {
      std::vector<Vec3> points;
      for (std::size_t i = 0; i < n; ++i) {
        points.push_back(test::randomPoint(rng, Aabb{Vec3::Constant(-5), Vec3::Constant(5)}));
      }
      std::vector<double> out(n, 12345.0), program(n, 12345.0);
      tree.values(points, out, ops);
      TreeProgram(tree).values(points, program, ops);
      for (std::size_t i = 0; i < n; ++i) {
        const double v = tree.value(points[i], ops);
        ASSERT_EQ(out[i], v) << t;
        ASSERT_EQ(program[i], v) << t;
        ASSERT_EQ(tree.evaluate(points[i], ops).f, v) << t;
        blended += v != tree.value(points[i]);
      }
    }
  }
  EXPECT_GT(blended, 1000u);
  // The built-in kinds through the same overload.
  const CsgTree tree = test::randomTree(rng, 5);
  std::vector<Vec3> points;
  for (int i = 0; i < 300; ++i) {
    points.push_back(test::randomPoint(rng, Aabb{Vec3::Constant(-5), Vec3::Constant(5)}));
  }
  for (const SetOperations* ops : {&minMaxOperations(), &rFunctionOperations()}) {
    std::vector<double> out(points.size());
    tree.values(points, out, *ops);
    for (std::size_t i = 0; i < points.size(); ++i) ASSERT_EQ(out[i], tree.value(points[i], *ops));
  }
}

}  // namespace
}  // namespace csgvox
