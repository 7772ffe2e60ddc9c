#include "core/clipped_solid.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace csgvox {
namespace {

void requireUnitAxis(const Vec3& v, const char* what) {
  if (!v.allFinite() || std::abs(v.norm() - 1.0) > 1e-6) {
    throw std::invalid_argument(std::string("clippedSolid: the ") + what +
                                " must be a finite unit vector");
  }
}

void requireFinitePoint(const Vec3& v, const char* what) {
  if (!v.allFinite()) {
    throw std::invalid_argument(std::string("clippedSolid: the ") + what + " must be finite");
  }
}

// The largest distance from p to a point of the box (at one of its corners).
double farthestDistance(const Aabb& box, const Vec3& p) {
  const Vec3 far = (box.min - p).cwiseAbs().cwiseMax((box.max - p).cwiseAbs());
  return far.norm();
}

Primitive cylinderSolid(const CylinderSurface& s, const Aabb& box) {
  requireUnitAxis(s.axisDir, "cylinder axis");
  requireFinitePoint(s.axisPoint, "cylinder axis point");
  const Vec3 c = box.center();
  const Vec3 center = s.axisPoint + (c - s.axisPoint).dot(s.axisDir) * s.axisDir;
  // Every point q of the box has |(q - center)·axis| <= halfAlong.
  const double halfAlong = s.axisDir.cwiseAbs().dot(0.5 * box.size());
  Cylinder cyl;
  cyl.center = center;
  cyl.axis = s.axisDir;
  cyl.radius = s.radius;
  cyl.height = 2.0 * (halfAlong + box.diagonal() + s.radius);
  return cyl;
}

Primitive coneSolid(const ConeSurface& s, const Aabb& box) {
  requireUnitAxis(s.axisDir, "cone axis");
  requireFinitePoint(s.apex, "cone apex");
  if (!std::isfinite(s.halfAngle) || !(s.halfAngle > 0.0) ||
      !(s.halfAngle < 0.5 * std::numbers::pi)) {
    throw std::invalid_argument("clippedSolid: the cone half-angle must be in (0, pi/2) radians");
  }
  double height = 2.0 * farthestDistance(box, s.apex) + box.diagonal();
  if (!(height > 0.0)) height = 1.0;  // the box is the apex alone: any height is exact there
  Cone cone;
  cone.center = s.apex + 0.5 * height * s.axisDir;
  cone.axis = s.axisDir;
  cone.radiusBottom = 0.0;
  cone.radiusTop = height * std::tan(s.halfAngle);
  cone.height = height;
  return cone;
}

}  // namespace

Primitive clippedSolid(const SurfaceShape& shape, const Aabb& box) {
  if (box.isEmpty() || !box.isBounded()) {
    throw std::invalid_argument("clippedSolid: the box is empty or unbounded");
  }
  const Primitive solid = std::visit(
      [&box](const auto& s) -> Primitive {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, PlaneSurface>) {
          return HalfSpace{s.normal, s.offset};
        } else if constexpr (std::is_same_v<S, CylinderSurface>) {
          return cylinderSolid(s, box);
        } else if constexpr (std::is_same_v<S, ConeSurface>) {
          return coneSolid(s, box);
        } else if constexpr (std::is_same_v<S, SphereSurface>) {
          return Sphere{s.center, s.radius};
        } else {
          Torus t;
          t.center = s.center;
          t.axis = s.axisDir;
          t.majorRadius = s.majorRadius;
          t.minorRadius = s.minorRadius;
          return t;
        }
      },
      shape);
  try {
    solid.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("clippedSolid: ") + e.what());
  }
  return solid;
}

}  // namespace csgvox
