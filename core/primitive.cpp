#include "core/primitive.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>

namespace csgvox {
namespace {

constexpr double kPi = std::numbers::pi;

// Signed distance in the usual convention (negative inside) with gradient, in
// the (rho, z) meridian half-plane of a solid of revolution.
struct Sd2 {
  double d;
  double gRho;
  double gZ;
};

// Cylindrical coordinates of p around an axis through `center`.
struct Meridian {
  double rho;   // distance from the axis
  double z;     // signed coordinate along the axis
  Vec3 radial;  // unit radial direction (arbitrary perpendicular on the axis)
};

// The radial direction is only computed with kGradient.
template <bool kGradient>
[[gnu::always_inline]] inline Meridian toMeridian(const Vec3& p, const Vec3& center,
                                                  const Vec3& axis) {
  const Vec3 d = p - center;
  const double z = d.dot(axis);
  const Vec3 r = d - z * axis;
  const double rho = r.norm();
  Meridian m{rho, z, Vec3::Zero()};
  if constexpr (!kGradient) {
    return m;
  } else if (rho > 1e-300) {
    m.radial = r / rho;
  } else {
    m.radial = frameFromAxis(axis).col(0);
  }
  return m;
}

// Returns f = -sd and, with kGradient, the 3D gradient of f.
template <bool kGradient>
double fromMeridian(const Sd2& s, const Meridian& m, const Vec3& axis, Vec3* gradient) {
  if constexpr (kGradient) *gradient = -(s.gRho * m.radial + s.gZ * axis);
  return -s.d;
}

// Signed distance of a 2D box [-hx,hx]x[-hz,hz] centred at the origin, for a
// point given in |coordinates| (qx, qz >= 0 side), with gradient w.r.t. qx, qz.
[[gnu::always_inline]] inline Sd2 boxSd2(double qx, double qz, double hx, double hz) {
  const double dx = qx - hx;
  const double dz = qz - hz;
  if (dx > 0.0 && dz > 0.0) {
    const double len = std::hypot(dx, dz);
    return {len, dx / len, dz / len};
  }
  if (dx >= dz) return {std::max(dx, 0.0) + std::min(dx, 0.0), 1.0, 0.0};
  return {std::max(dz, 0.0) + std::min(dz, 0.0), 0.0, 1.0};
}

// Signed distance to a convex polygon given counter-clockwise by its boundary
// segments (x = rho, y = z). Only the listed segments count as boundary.
struct Segment2 {
  double ax, ay, bx, by;
};

Sd2 convexSd2(double x, double y, const Segment2* segs, int count) {
  bool outside = false;
  double bestInside = -std::numeric_limits<double>::infinity();
  double gInX = 0.0, gInY = 0.0;
  double bestOut = std::numeric_limits<double>::infinity();
  double gOutX = 0.0, gOutY = 0.0;
  for (int i = 0; i < count; ++i) {
    const Segment2& s = segs[i];
    const double ex = s.bx - s.ax, ey = s.by - s.ay;
    const double len = std::hypot(ex, ey);
    if (len <= 0.0) continue;
    // Outward normal of a counter-clockwise polygon edge.
    const double nx = ey / len, ny = -ex / len;
    const double line = (x - s.ax) * nx + (y - s.ay) * ny;
    if (line > 0.0) outside = true;
    if (line > bestInside) {
      bestInside = line;
      gInX = nx;
      gInY = ny;
    }
    const double t = std::clamp(((x - s.ax) * ex + (y - s.ay) * ey) / (len * len), 0.0, 1.0);
    const double vx = x - (s.ax + t * ex), vy = y - (s.ay + t * ey);
    const double dist = std::hypot(vx, vy);
    if (dist < bestOut) {
      bestOut = dist;
      // Within rounding of the edge the difference vector has no reliable
      // direction: use the edge's normal (the limit of that direction).
      if (dist > 1e-12 * (len + std::abs(x) + std::abs(y))) {
        gOutX = vx / dist;
        gOutY = vy / dist;
      } else {
        gOutX = nx;
        gOutY = ny;
      }
    }
  }
  if (outside) return {bestOut, gOutX, gOutY};
  return {bestInside, gInX, gInY};
}

// The primitives' signed distances; the gradient is written to *g with
// kGradient only (the value is computed the same way either way).
template <bool kGradient>
double halfSpaceValue(const HalfSpace& s, const Vec3& p, Vec3* g) {
  if constexpr (kGradient) *g = -s.normal;
  return s.offset - s.normal.dot(p);
}

template <bool kGradient>
double boxValue(const Box& s, const Vec3& p, Vec3* g) {
  const Vec3 local = s.axes.transpose() * (p - s.center);
  const Vec3 q = local.cwiseAbs() - s.halfSize;
  Vec3 gl;
  double sd;
  if ((q.array() > 0.0).any()) {
    const Vec3 pos = q.cwiseMax(0.0);
    sd = pos.norm();
    if constexpr (kGradient) gl = pos / sd;
  } else {
    int k = 0;
    for (int i = 1; i < 3; ++i) {
      if (q[i] > q[k]) k = i;
    }
    sd = q[k];
    if constexpr (kGradient) gl = Vec3::Unit(k);
  }
  if constexpr (kGradient) {
    for (int i = 0; i < 3; ++i) {
      if (local[i] < 0.0) gl[i] = -gl[i];
    }
    *g = -(s.axes * gl);
  }
  return -sd;
}

template <bool kGradient>
double cylinderValue(const Cylinder& s, const Vec3& p, Vec3* g) {
  const Meridian m = toMeridian<kGradient>(p, s.center, s.axis);
  Sd2 sd = boxSd2(m.rho, std::abs(m.z), s.radius, 0.5 * s.height);
  if (m.z < 0.0) sd.gZ = -sd.gZ;
  return fromMeridian<kGradient>(sd, m, s.axis, g);
}

template <bool kGradient>
double coneValue(const Cone& s, const Vec3& p, Vec3* g) {
  const Meridian m = toMeridian<kGradient>(p, s.center, s.axis);
  const double h = 0.5 * s.height;
  // Counter-clockwise trapezoid in (rho, z); the axis edge is not a boundary.
  const std::array<Segment2, 3> segs = {{
      {0.0, -h, s.radiusBottom, -h},         // bottom cap
      {s.radiusBottom, -h, s.radiusTop, h},  // lateral surface
      {s.radiusTop, h, 0.0, h},              // top cap
  }};
  const Sd2 sd = convexSd2(m.rho, m.z, segs.data(), static_cast<int>(segs.size()));
  return fromMeridian<kGradient>(sd, m, s.axis, g);
}

template <bool kGradient>
double sphereValue(const Sphere& s, const Vec3& p, Vec3* g) {
  const Vec3 d = p - s.center;
  const double len = d.norm();
  if constexpr (kGradient) *g = len > 0.0 ? Vec3(-d / len) : Vec3(-Vec3::UnitZ());
  return s.radius - len;
}

template <bool kGradient>
double torusValue(const Torus& s, const Vec3& p, Vec3* g) {
  const Meridian m = toMeridian<kGradient>(p, s.center, s.axis);
  const double qx = m.rho - s.majorRadius;
  const double len = std::hypot(qx, m.z);
  Sd2 sd{len - s.minorRadius, 1.0, 0.0};
  if (len > 0.0) {
    sd.gRho = qx / len;
    sd.gZ = m.z / len;
  }
  return fromMeridian<kGradient>(sd, m, s.axis, g);
}

template <bool kGradient>
double shapeValue(const Primitive& prim, const Vec3& p, Vec3* g) {
  switch (prim.type()) {
    case PrimitiveType::HalfSpace:
      return halfSpaceValue<kGradient>(*prim.as<HalfSpace>(), p, g);
    case PrimitiveType::Box:
      return boxValue<kGradient>(*prim.as<Box>(), p, g);
    case PrimitiveType::Cylinder:
      return cylinderValue<kGradient>(*prim.as<Cylinder>(), p, g);
    case PrimitiveType::Cone:
      return coneValue<kGradient>(*prim.as<Cone>(), p, g);
    case PrimitiveType::Sphere:
      return sphereValue<kGradient>(*prim.as<Sphere>(), p, g);
    case PrimitiveType::Torus:
      return torusValue<kGradient>(*prim.as<Torus>(), p, g);
  }
  return 0.0;
}

// out[i] = value of `shape` at points[i]: one loop per shape type.
template <auto kValue, class Shape>
void valuesOf(const Shape& shape, std::span<const Vec3> points, std::span<double> out) {
  for (std::size_t i = 0; i < points.size(); ++i) out[i] = kValue(shape, points[i], nullptr);
}

// Mixes v into the hash h (64-bit).
std::size_t mix(std::size_t h, std::uint64_t v) {
  v *= 0x9e3779b97f4a7c15ull;
  v ^= v >> 32;
  return (h ^ v) * 0x100000001b3ull + 0x7f4a7c159e3779b9ull;
}

std::size_t mix(std::size_t h, double x) {
  return mix(h, std::bit_cast<std::uint64_t>(x == 0.0 ? 0.0 : x));  // -0 == 0
}

std::size_t mix(std::size_t h, const Vec3& v) { return mix(mix(mix(h, v.x()), v.y()), v.z()); }

// Half extent along world axis k of a disc of radius r perpendicular to `axis`.
Vec3 discExtent(const Vec3& axis, double r) {
  Vec3 e;
  for (int k = 0; k < 3; ++k) e[k] = r * std::sqrt(std::max(0.0, 1.0 - axis[k] * axis[k]));
  return e;
}

bool finite(const Vec3& v) { return v.allFinite(); }

void requireUnit(const Vec3& v, const char* what) {
  if (!finite(v) || std::abs(v.norm() - 1.0) > 1e-6) {
    throw std::invalid_argument(std::string(what) + " must be a finite unit vector");
  }
}

void requirePositive(double x, const char* what) {
  if (!std::isfinite(x) || !(x > 0.0)) {
    throw std::invalid_argument(std::string(what) + " must be finite and > 0");
  }
}

bool near(const Vec3& a, const Vec3& b, double tol) { return (a - b).cwiseAbs().maxCoeff() <= tol; }
bool near(double a, double b, double tol) { return std::abs(a - b) <= tol; }

}  // namespace

double Primitive::value(const Vec3& p) const { return shapeValue<false>(*this, p, nullptr); }

double Primitive::valueAndGradient(const Vec3& p, Vec3& gradient) const {
  return shapeValue<true>(*this, p, &gradient);
}

void Primitive::values(std::span<const Vec3> points, std::span<double> out) const {
  if (points.size() != out.size()) {
    throw std::invalid_argument("Primitive::values: points and out differ in size");
  }
  switch (type()) {
    case PrimitiveType::HalfSpace:
      return valuesOf<halfSpaceValue<false>>(*as<HalfSpace>(), points, out);
    case PrimitiveType::Box:
      return valuesOf<boxValue<false>>(*as<Box>(), points, out);
    case PrimitiveType::Cylinder:
      return valuesOf<cylinderValue<false>>(*as<Cylinder>(), points, out);
    case PrimitiveType::Cone:
      return valuesOf<coneValue<false>>(*as<Cone>(), points, out);
    case PrimitiveType::Sphere:
      return valuesOf<sphereValue<false>>(*as<Sphere>(), points, out);
    case PrimitiveType::Torus:
      return valuesOf<torusValue<false>>(*as<Torus>(), points, out);
  }
}

std::size_t Primitive::hash() const {
  std::size_t h = mix(std::size_t{0}, std::uint64_t(type()) + 1);
  std::visit(
      [&h](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, HalfSpace>) {
          h = mix(mix(h, s.normal), s.offset);
        } else if constexpr (std::is_same_v<S, Box>) {
          h = mix(mix(mix(mix(h, s.center), Vec3(s.axes.col(0))), Vec3(s.axes.col(1))),
                  Vec3(s.axes.col(2)));
          h = mix(h, s.halfSize);
        } else if constexpr (std::is_same_v<S, Cylinder>) {
          h = mix(mix(mix(mix(h, s.center), s.axis), s.radius), s.height);
        } else if constexpr (std::is_same_v<S, Cone>) {
          h = mix(mix(mix(mix(mix(h, s.center), s.axis), s.radiusBottom), s.radiusTop), s.height);
        } else if constexpr (std::is_same_v<S, Sphere>) {
          h = mix(mix(h, s.center), s.radius);
        } else {
          h = mix(mix(mix(mix(h, s.center), s.axis), s.majorRadius), s.minorRadius);
        }
      },
      shape_);
  return h;
}

Aabb Primitive::bounds() const {
  Aabb b;
  switch (type()) {
    case PrimitiveType::HalfSpace:
      return Aabb::everything();
    case PrimitiveType::Box: {
      const Box& s = *as<Box>();
      const Vec3 e = s.axes.cwiseAbs() * s.halfSize;
      b.min = s.center - e;
      b.max = s.center + e;
      return b;
    }
    case PrimitiveType::Cylinder: {
      const Cylinder& s = *as<Cylinder>();
      const Vec3 e = discExtent(s.axis, s.radius) + 0.5 * s.height * s.axis.cwiseAbs();
      b.min = s.center - e;
      b.max = s.center + e;
      return b;
    }
    case PrimitiveType::Cone: {
      const Cone& s = *as<Cone>();
      const Vec3 bottom = s.center - 0.5 * s.height * s.axis;
      const Vec3 top = s.center + 0.5 * s.height * s.axis;
      const Vec3 eb = discExtent(s.axis, s.radiusBottom);
      const Vec3 et = discExtent(s.axis, s.radiusTop);
      b.extend(Vec3(bottom - eb));
      b.extend(Vec3(bottom + eb));
      b.extend(Vec3(top - et));
      b.extend(Vec3(top + et));
      return b;
    }
    case PrimitiveType::Sphere: {
      const Sphere& s = *as<Sphere>();
      b.min = s.center.array() - s.radius;
      b.max = s.center.array() + s.radius;
      return b;
    }
    case PrimitiveType::Torus: {
      // The torus is its centre circle swept by a ball of the minor radius.
      const Torus& s = *as<Torus>();
      const Vec3 e = discExtent(s.axis, s.majorRadius).array() + s.minorRadius;
      b.min = s.center - e;
      b.max = s.center + e;
      return b;
    }
  }
  return b;
}

double Primitive::volume() const {
  switch (type()) {
    case PrimitiveType::HalfSpace:
      return std::numeric_limits<double>::infinity();
    case PrimitiveType::Box:
      return 8.0 * as<Box>()->halfSize.prod();
    case PrimitiveType::Cylinder: {
      const Cylinder& s = *as<Cylinder>();
      return kPi * s.radius * s.radius * s.height;
    }
    case PrimitiveType::Cone: {
      const Cone& s = *as<Cone>();
      const double a = s.radiusBottom, b = s.radiusTop;
      return kPi * s.height / 3.0 * (a * a + a * b + b * b);
    }
    case PrimitiveType::Sphere: {
      const double r = as<Sphere>()->radius;
      return 4.0 / 3.0 * kPi * r * r * r;
    }
    case PrimitiveType::Torus: {
      const Torus& s = *as<Torus>();
      return 2.0 * kPi * kPi * s.majorRadius * s.minorRadius * s.minorRadius;
    }
  }
  return 0.0;
}

std::vector<Vec3> Primitive::directions() const {
  if (const auto* h = as<HalfSpace>()) return {h->normal};
  if (const auto* b = as<Box>()) return {b->axes.col(0), b->axes.col(1), b->axes.col(2)};
  if (const auto* c = as<Cylinder>()) return {c->axis};
  if (const auto* c = as<Cone>()) return {c->axis};
  if (const auto* t = as<Torus>()) return {t->axis};
  return {};
}

double Primitive::surfaceArea() const {
  switch (type()) {
    case PrimitiveType::HalfSpace:
      return std::numeric_limits<double>::infinity();
    case PrimitiveType::Box: {
      const Vec3& h = as<Box>()->halfSize;
      return 8.0 * (h.x() * h.y() + h.y() * h.z() + h.x() * h.z());
    }
    case PrimitiveType::Cylinder: {
      const Cylinder& s = *as<Cylinder>();
      return 2.0 * kPi * s.radius * (s.height + s.radius);
    }
    case PrimitiveType::Cone: {
      const Cone& s = *as<Cone>();
      const double a = s.radiusBottom, b = s.radiusTop;
      const double slant = std::hypot(a - b, s.height);
      return kPi * (a + b) * slant + kPi * (a * a + b * b);
    }
    case PrimitiveType::Sphere: {
      const double r = as<Sphere>()->radius;
      return 4.0 * kPi * r * r;
    }
    case PrimitiveType::Torus: {
      const Torus& s = *as<Torus>();
      return 4.0 * kPi * kPi * s.majorRadius * s.minorRadius;
    }
  }
  return 0.0;
}

void Primitive::validate() const {
  switch (type()) {
    case PrimitiveType::HalfSpace: {
      const HalfSpace& s = *as<HalfSpace>();
      requireUnit(s.normal, "halfspace normal");
      if (!std::isfinite(s.offset)) throw std::invalid_argument("halfspace offset must be finite");
      return;
    }
    case PrimitiveType::Box: {
      const Box& s = *as<Box>();
      if (!finite(s.center)) throw std::invalid_argument("box center must be finite");
      for (int i = 0; i < 3; ++i) {
        requireUnit(s.axes.col(i), "box axis");
        requirePositive(s.halfSize[i], "box half size");
      }
      if ((s.axes.transpose() * s.axes - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
          s.axes.determinant() < 0.0) {
        throw std::invalid_argument("box axes must form a right-handed orthonormal frame");
      }
      return;
    }
    case PrimitiveType::Cylinder: {
      const Cylinder& s = *as<Cylinder>();
      if (!finite(s.center)) throw std::invalid_argument("cylinder center must be finite");
      requireUnit(s.axis, "cylinder axis");
      requirePositive(s.radius, "cylinder radius");
      requirePositive(s.height, "cylinder height");
      return;
    }
    case PrimitiveType::Cone: {
      const Cone& s = *as<Cone>();
      if (!finite(s.center)) throw std::invalid_argument("cone center must be finite");
      requireUnit(s.axis, "cone axis");
      requirePositive(s.height, "cone height");
      if (!std::isfinite(s.radiusBottom) || !std::isfinite(s.radiusTop) || s.radiusBottom < 0.0 ||
          s.radiusTop < 0.0 || s.radiusBottom + s.radiusTop <= 0.0) {
        throw std::invalid_argument("cone radii must be finite, >= 0 and not both 0");
      }
      return;
    }
    case PrimitiveType::Sphere: {
      const Sphere& s = *as<Sphere>();
      if (!finite(s.center)) throw std::invalid_argument("sphere center must be finite");
      requirePositive(s.radius, "sphere radius");
      return;
    }
    case PrimitiveType::Torus: {
      const Torus& s = *as<Torus>();
      if (!finite(s.center)) throw std::invalid_argument("torus center must be finite");
      requireUnit(s.axis, "torus axis");
      requirePositive(s.majorRadius, "torus major radius");
      requirePositive(s.minorRadius, "torus minor radius");
      if (s.minorRadius > s.majorRadius) {
        throw std::invalid_argument("torus minor radius must not exceed the major radius");
      }
      return;
    }
  }
}

bool Primitive::approxEqual(const Primitive& other, double tol) const {
  if (type() != other.type()) return false;
  switch (type()) {
    case PrimitiveType::HalfSpace: {
      const HalfSpace &a = *as<HalfSpace>(), &b = *other.as<HalfSpace>();
      return near(a.normal, b.normal, tol) && near(a.offset, b.offset, tol);
    }
    case PrimitiveType::Box: {
      const Box &a = *as<Box>(), &b = *other.as<Box>();
      return near(a.center, b.center, tol) && near(a.halfSize, b.halfSize, tol) &&
             (a.axes - b.axes).cwiseAbs().maxCoeff() <= tol;
    }
    case PrimitiveType::Cylinder: {
      const Cylinder &a = *as<Cylinder>(), &b = *other.as<Cylinder>();
      return near(a.center, b.center, tol) && near(a.axis, b.axis, tol) &&
             near(a.radius, b.radius, tol) && near(a.height, b.height, tol);
    }
    case PrimitiveType::Cone: {
      const Cone &a = *as<Cone>(), &b = *other.as<Cone>();
      return near(a.center, b.center, tol) && near(a.axis, b.axis, tol) &&
             near(a.radiusBottom, b.radiusBottom, tol) && near(a.radiusTop, b.radiusTop, tol) &&
             near(a.height, b.height, tol);
    }
    case PrimitiveType::Sphere: {
      const Sphere &a = *as<Sphere>(), &b = *other.as<Sphere>();
      return near(a.center, b.center, tol) && near(a.radius, b.radius, tol);
    }
    case PrimitiveType::Torus: {
      const Torus &a = *as<Torus>(), &b = *other.as<Torus>();
      return near(a.center, b.center, tol) && near(a.axis, b.axis, tol) &&
             near(a.majorRadius, b.majorRadius, tol) && near(a.minorRadius, b.minorRadius, tol);
    }
  }
  return false;
}

std::string_view primitiveTypeName(PrimitiveType type) {
  // In the order of PrimitiveType.
  static constexpr std::array<std::string_view, 6> kNames = {"halfspace", "box",    "cylinder",
                                                             "cone",      "sphere", "torus"};
  const auto i = static_cast<std::size_t>(type);
  return i < kNames.size() ? kNames[i] : "unknown";
}

PrimitiveType primitiveTypeFromName(std::string_view name) {
  for (PrimitiveType t : {PrimitiveType::HalfSpace, PrimitiveType::Box, PrimitiveType::Cylinder,
                          PrimitiveType::Cone, PrimitiveType::Sphere, PrimitiveType::Torus}) {
    if (primitiveTypeName(t) == name) return t;
  }
  throw std::invalid_argument("unknown primitive type '" + std::string(name) + "'");
}

}  // namespace csgvox
