#pragma once
/// Fitted surfaces: the unbounded surfaces detected in a scan (planes,
/// cylinders, cones, spheres, tori), each with the scan points it explains.

#include <cstdint>
#include <optional>
#include <string_view>
#include <variant>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// Kind of a fitted surface.
enum class SurfaceType { Plane, Cylinder, Cone, Sphere, Torus };

/// The plane normal·x = offset; normal is unit and agrees with the inliers'
/// outward normals.
struct PlaneSurface {
  Vec3 normal = Vec3::UnitZ();  ///< unit, outward (as the scan normals)
  double offset = 0.0;          ///< signed distance of the plane from the origin
};

/// An infinite circular cylinder.
struct CylinderSurface {
  Vec3 axisPoint = Vec3::Zero();  ///< a point on the axis
  Vec3 axisDir = Vec3::UnitZ();   ///< unit axis direction
  double radius = 1.0;
};

/// An infinite (one-sided) circular cone.
struct ConeSurface {
  Vec3 apex = Vec3::Zero();
  Vec3 axisDir = Vec3::UnitZ();  ///< unit, from the apex into the cone
  double halfAngle = 0.5;        ///< radians, in (0, pi/2)
};

/// A sphere.
struct SphereSurface {
  Vec3 center = Vec3::Zero();
  double radius = 1.0;
};

/// A ring torus.
struct TorusSurface {
  Vec3 center = Vec3::Zero();
  Vec3 axisDir = Vec3::UnitZ();  ///< unit axis of revolution
  double majorRadius = 1.0;
  double minorRadius = 0.25;
};

/// Parameters of a fitted surface.
using SurfaceShape =
    std::variant<PlaneSurface, CylinderSurface, ConeSurface, SphereSurface, TorusSurface>;

/// A fitted surface with its inlier points (indices into the scan).
struct Surface {
  SurfaceShape shape;
  std::vector<std::uint32_t> inliers;  ///< indices of the scan points it explains
  double rms = 0.0;                    ///< RMS geometric distance of the inliers, scan units
  /// For curved surfaces: true when the scan normals point away from the
  /// axis/centre (a convex feature such as a boss or a shaft), false when
  /// they point towards it (a hole or a concave fillet).
  bool convex = true;

  SurfaceType type() const { return static_cast<SurfaceType>(shape.index()); }
  template <class T>
  const T* as() const {
    return std::get_if<T>(&shape);
  }
};

/// Euclidean distance (>= 0) from p to the (unbounded) surface.
double surfaceDistance(const Surface& surface, const Vec3& p);

/// The direction a surface shows, unit: a plane's normal, or the axis of a
/// cylinder, cone or torus; none for a sphere (or a zero vector).
std::optional<Vec3> surfaceDirection(const Surface& surface);

/// Lower-case name used in files: "plane", "cylinder", "cone", "sphere", "torus".
std::string_view surfaceTypeName(SurfaceType type);

}  // namespace csgvox
