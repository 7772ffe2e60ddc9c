#pragma once
/// The solid enclosed by a closed triangle mesh, voxelised for fast
/// inside/outside queries (e.g. the volumetric IoU between a reference mesh
/// and a CSG tree).

#include <memory>

#include "core/triangle_mesh.h"

namespace csgvox {

/// An immutable voxelised solid bounded by a closed triangle mesh. Queries are
/// exact to about a voxel near the surface and exact elsewhere; the mesh's
/// orientation does not matter. Copies share the voxel data; concurrent
/// queries are safe.
class MeshSolid {
 public:
  /// Voxelises the solid of `mesh` with cubic voxels of side `voxelSize`
  /// (scan units). The mesh must be closed in the sense that every edge is
  /// used by an even number of triangles (non-manifold edges are accepted).
  /// @throw std::invalid_argument when the mesh is empty, has a boundary edge,
  ///        a non-finite vertex or an index out of range, when `voxelSize` is
  ///        not > 0, or when the mesh spans more than 4096 voxels along an axis.
  MeshSolid(const TriangleMesh& mesh, double voxelSize);

  /// True when p lies inside the solid (or within a tiny fraction of a voxel
  /// of its surface).
  bool contains(const Vec3& p) const;
  /// The voxel size the solid was built with, in scan units.
  double voxelSize() const;
  /// Axis-aligned bounds of the mesh.
  Aabb bounds() const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace csgvox
