#include "core/surface.h"

#include <algorithm>
#include <cmath>

namespace csgvox {

std::optional<Vec3> surfaceDirection(const Surface& surface) {
  Vec3 d;
  if (const auto* p = surface.as<PlaneSurface>()) {
    d = p->normal;
  } else if (const auto* c = surface.as<CylinderSurface>()) {
    d = c->axisDir;
  } else if (const auto* k = surface.as<ConeSurface>()) {
    d = k->axisDir;
  } else if (const auto* t = surface.as<TorusSurface>()) {
    d = t->axisDir;
  } else {
    return std::nullopt;
  }
  if (!(d.norm() > 0.0)) return std::nullopt;
  return d.normalized();
}

double surfaceDistance(const Surface& surface, const Vec3& p) {
  switch (surface.type()) {
    case SurfaceType::Plane: {
      const PlaneSurface& s = *surface.as<PlaneSurface>();
      return std::abs(s.normal.dot(p) - s.offset);
    }
    case SurfaceType::Cylinder: {
      const CylinderSurface& s = *surface.as<CylinderSurface>();
      const Vec3 d = p - s.axisPoint;
      return std::abs((d - d.dot(s.axisDir) * s.axisDir).norm() - s.radius);
    }
    case SurfaceType::Cone: {
      const ConeSurface& s = *surface.as<ConeSurface>();
      const Vec3 d = p - s.apex;
      const double z = d.dot(s.axisDir);
      const double rho = (d - z * s.axisDir).norm();
      // Distance to the generating ray (cos a, sin a) in the (z, rho) plane.
      const double c = std::cos(s.halfAngle), sn = std::sin(s.halfAngle);
      const double along = z * c + rho * sn;
      if (along <= 0.0) return d.norm();
      return std::abs(-z * sn + rho * c);
    }
    case SurfaceType::Sphere: {
      const SphereSurface& s = *surface.as<SphereSurface>();
      return std::abs((p - s.center).norm() - s.radius);
    }
    case SurfaceType::Torus: {
      const TorusSurface& s = *surface.as<TorusSurface>();
      const Vec3 d = p - s.center;
      const double z = d.dot(s.axisDir);
      const double rho = (d - z * s.axisDir).norm();
      return std::abs(std::hypot(rho - s.majorRadius, z) - s.minorRadius);
    }
  }
  return 0.0;
}

std::string_view surfaceTypeName(SurfaceType type) {
  switch (type) {
    case SurfaceType::Plane:
      return "plane";
    case SurfaceType::Cylinder:
      return "cylinder";
    case SurfaceType::Cone:
      return "cone";
    case SurfaceType::Sphere:
      return "sphere";
    case SurfaceType::Torus:
      return "torus";
  }
  return "unknown";
}

}  // namespace csgvox
