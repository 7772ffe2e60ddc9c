#pragma once
/// The one question a scanner asks of a part: where does a ray from outside
/// first meet its surface, and with which outward normal. Implemented exactly
/// on a CSG tree's field (tree_caster.h) and on a triangle mesh
/// (mesh_caster.h), so that the camera and noise model (scanner.h) is shared.

#include <optional>
#include <utility>

#include "core/geometry.h"

namespace csgvox {

/// The first surface point a ray meets.
struct RayHit {
  double distance = 0.0;        ///< along the unit direction, from the ray's origin (scan units)
  Vec3 normal = Vec3::UnitZ();  ///< unit outward normal of the surface at the hit
};

/// A surface that rays can be cast at. Implementations are immutable and safe
/// to call from several threads at once.
class RayCaster {
 public:
  virtual ~RayCaster() = default;
  /// Axis-aligned bounds of the surface (non-empty and bounded).
  virtual Aabb bounds() const = 0;
  /// The first hit of the ray origin + t·direction, 0 <= t <= maxDistance
  /// (`direction` unit), or nothing when it misses. The origin is outside
  /// the solid.
  virtual std::optional<RayHit> firstHit(const Vec3& origin, const Vec3& direction,
                                         double maxDistance) const = 0;
};

/// The parameter interval [enter, exit] where the ray origin + t·direction
/// crosses `box`, clipped to [0, maxDistance]; nothing when it misses.
std::optional<std::pair<double, double>> rayBoxInterval(const Aabb& box, const Vec3& origin,
                                                        const Vec3& direction, double maxDistance);

}  // namespace csgvox
