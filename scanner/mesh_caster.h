#pragma once
/// Rays cast at a triangle mesh (CGAL's AABB tree), for parts given as meshes
/// such as the InverseCSG benchmark's.

#include <memory>

#include "core/triangle_mesh.h"
#include "scanner/ray_caster.h"

namespace csgvox {

/// A RayCaster on a triangle mesh: the first triangle a ray meets, with the
/// triangle's normal (triangles counter-clockwise seen from outside). The
/// mesh should be closed for a scan to be the scan of a solid.
class MeshCaster final : public RayCaster {
 public:
  /// @throw std::invalid_argument if the mesh has no triangle of non-zero
  ///        area or an index out of range.
  explicit MeshCaster(const TriangleMesh& mesh);
  ~MeshCaster() override;
  MeshCaster(const MeshCaster&) = delete;
  MeshCaster& operator=(const MeshCaster&) = delete;

  Aabb bounds() const override { return bounds_; }
  std::optional<RayHit> firstHit(const Vec3& origin, const Vec3& direction,
                                 double maxDistance) const override;

 private:
  struct Impl;
  std::unique_ptr<const Impl> impl_;
  Aabb bounds_;
};

}  // namespace csgvox
