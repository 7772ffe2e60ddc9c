#pragma once
/// SARDF set operations (signed approximate real distance functions, Fayolle,
/// Pasko et al., "An evolutionary approach to the extraction of object
/// construction trees", appended paper §3.2): union and intersection of two
/// FRep values (f >= 0 inside) that replace the corner of min/max by circular
/// arcs, with a radius R bounding how far the arcs reach.
///
/// Union f1 ∪S f2, written with hi = max(f1, f2) and lo = min(f1, f2):
///  - opposite signs (lo <= 0 <= hi): hi, exactly as max;
///  - both > 0, zone I (lo < R, or (hi − R)² + (lo − R)² < R²): inside the
///    wedge lo/hi > 1/2 the level curve c is the circle of centre (c/2, c/2)
///    and radius c/2, c = 2(hi + lo) − 2·sqrt(2·hi·lo); hi outside the wedge;
///  - both > 0, zone II (elsewhere): inside the band hi − lo < R the level
///    curve c is the circle of centre (c − R, c − R) and radius R,
///    c = ((hi + lo + 2R) − sqrt(2R² − (hi − lo)²)) / 2; hi outside the band;
///  - both < 0, zone I (hi > −R, or lo > −2R and (hi + 2R)² + (lo + 2R)² > R²):
///    inside the wedge lo/hi < 2 the level curve c is the circle of centre
///    (2c, 2c) and radius |c|, c = (4(hi + lo) − sqrt(32·hi·lo − 12(hi² + lo²))) / 14;
///    hi outside the wedge;
///  - both < 0, zone II (elsewhere): the zone II form of the positive case.
/// (The paper prints the negative case with its roots' signs and its f1/f2
/// branches exchanged; the forms above are the ones whose level curves are the
/// circles it describes.) Intersection is −((−f1) ∪S (−f2)); difference is
/// f1 ∩S (−f2); complement is −f.
///
/// Properties (checked by tests/test_sardf.cpp):
///  - the sign is the sign of min/max everywhere, so the solid is unchanged;
///  - union >= max, intersection <= min, and both equal min/max wherever
///    |f1 − f2| >= R; the difference from min/max is at most (1 − 1/√2)·R;
///  - the value is continuous everywhere and C¹ everywhere except at
///    f1 = f2 = 0 (the sharp edge is kept) and on the zone boundary arcs (the
///    level curves c = 2R and c = −R of the union, −2R and R of the
///    intersection), where the gradient keeps its direction but its length
///    jumps (on the diagonal from 2(2 − √2) ≈ 1.17 to 1 for union of
///    positive values, from (4 + √2)/7 ≈ 0.77 to 1 for negative ones) — the
///    C¹ discontinuity on one level curve that the paper points out.
///
/// The functions are inline, reentrant and allocate nothing. They compute the
/// arcs from the ratio of the operands (homogeneous forms), so they neither
/// overflow nor underflow before the values themselves do, and every sqrt
/// argument is bounded away from zero (>= 1, >= 4 or >= R²): no guard against
/// negative rounding is needed. The *Value forms give the same f, bit for bit.

#include <cmath>

namespace csgvox {

/// A SARDF value and its partial derivatives with respect to the operands.
struct SardfResult {
  double f = 0.0;   ///< the combined value
  double d1 = 0.0;  ///< ∂f/∂f1
  double d2 = 0.0;  ///< ∂f/∂f2
};

/// The blending radius R used for a part of bounding-box diagonal `diagonal`:
/// 0.05·D (kSardfRadiusFraction). Inside R of the surface the growing arcs of
/// zone I apply, whose deviation from min/max is proportional to the value
/// (at most 17% of it for union of positive values, 23% for negative values):
/// the points a fitness looks at (within a few εd = 0.01·D of the surface)
/// all see these scale-free arcs, and their normals turn smoothly across an
/// edge instead of jumping. Farther out the error is capped at
/// (1 − 1/√2)·R ≈ 0.015·D, i.e. 1.5 εd, where the distance term of the
/// fitness is already negligible.
inline constexpr double kSardfRadiusFraction = 0.05;

/// R = kSardfRadiusFraction · `diagonal` (same length unit as the diagonal).
inline double sardfRadius(double diagonal) { return kSardfRadiusFraction * diagonal; }

namespace sardf_detail {

// Union of hi >= lo, with the derivatives with respect to hi and lo.
struct Ordered {
  double f, dHi, dLo;
};

// Zone II: arcs of radius r inside the band hi − lo < r.
template <bool kDerivatives>
inline Ordered band(double hi, double lo, double r) {
  const double d = hi - lo;  // >= 0
  if (!(d < r)) return {hi, 1.0, 0.0};
  const double h = std::sqrt(2.0 * r * r - d * d);  // in (r, √2·r]
  const double e = r - d;
  // ((hi + lo + 2r) − h) / 2 = hi + (r − d)² / (2r − d + h): >= hi exactly.
  Ordered o{hi + e * e / (2.0 * r - d + h), 1.0, 0.0};
  if constexpr (kDerivatives) {
    const double slope = 0.5 * (d / h);
    o.dHi = 0.5 + slope;
    o.dLo = 0.5 - slope;
  }
  return o;
}

template <bool kDerivatives>
inline Ordered uniteOrdered(double hi, double lo, double r) {
  if (lo > 0.0) {  // both inside
    const double a = hi - r, b = lo - r;
    if (!(lo < r || a * a + b * b < r * r)) return band<kDerivatives>(hi, lo, r);
    if (!(hi < 2.0 * lo)) return {hi, 1.0, 0.0};
    // Zone I: c = 2(hi + lo) − 2·sqrt(2·hi·lo) = hi·(1 + (s − 1)²), s = sqrt(2·lo/hi).
    const double s = std::sqrt(2.0 * (lo / hi));  // in (1, √2]
    const double e = s - 1.0;
    Ordered o{hi * (1.0 + e * e), 1.0, 0.0};
    if constexpr (kDerivatives) {
      o.dHi = 2.0 - s;
      o.dLo = 2.0 - 2.0 / s;
    }
    return o;
  }
  if (hi < 0.0) {  // both outside
    const double a = hi + 2.0 * r, b = lo + 2.0 * r;
    if (!(hi > -r || (lo > -2.0 * r && a * a + b * b > r * r)))
      return band<kDerivatives>(hi, lo, r);
    if (!(lo > 2.0 * hi)) return {hi, 1.0, 0.0};
    // Zone I: with t = lo/hi in [1, 2) and u = 2 − t (exact),
    // c = hi·(4(1 + t) + q)/14 = hi·(1 − 2u²/(2 + 4u + q)), q = sqrt(4 + 16u − 12u²).
    const double u = 2.0 - lo / hi;                           // in (0, 1]
    const double q = std::sqrt(4.0 + u * (16.0 - 12.0 * u));  // in [2, √8]
    Ordered o{hi * (1.0 - 2.0 * u * u / (2.0 + 4.0 * u + q)), 1.0, 0.0};
    if constexpr (kDerivatives) {
      o.dHi = (4.0 + (20.0 - 16.0 * u) / q) / 14.0;
      o.dLo = (4.0 + (12.0 * u - 8.0) / q) / 14.0;
    }
    return o;
  }
  return {hi, 1.0, 0.0};  // opposite signs, or a zero operand
}

}  // namespace sardf_detail

/// SARDF union of f1 and f2 with radius `radius` (> 0, finite) and its
/// partial derivatives. At a tie of the max branches (f1 = f2 = 0) the
/// derivative is that of f1, as min/max picks the first operand.
inline SardfResult sardfUnite(double f1, double f2, double radius) {
  if (f1 >= f2) {
    const sardf_detail::Ordered o = sardf_detail::uniteOrdered<true>(f1, f2, radius);
    return {o.f, o.dHi, o.dLo};
  }
  const sardf_detail::Ordered o = sardf_detail::uniteOrdered<true>(f2, f1, radius);
  return {o.f, o.dLo, o.dHi};
}

/// The f of sardfUnite, bit for bit, without derivatives.
inline double sardfUniteValue(double f1, double f2, double radius) {
  return f1 >= f2 ? sardf_detail::uniteOrdered<false>(f1, f2, radius).f
                  : sardf_detail::uniteOrdered<false>(f2, f1, radius).f;
}

/// SARDF intersection −((−f1) ∪S (−f2)) and its partial derivatives.
inline SardfResult sardfIntersect(double f1, double f2, double radius) {
  const SardfResult u = sardfUnite(-f1, -f2, radius);
  return {-u.f, u.d1, u.d2};
}

/// The f of sardfIntersect, bit for bit, without derivatives.
inline double sardfIntersectValue(double f1, double f2, double radius) {
  return -sardfUniteValue(-f1, -f2, radius);
}

}  // namespace csgvox
