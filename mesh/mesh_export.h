#pragma once
/// Turns a CSG tree into a closed triangle mesh: the tree's FRep is sampled
/// on a narrow band of voxels around its surface and the zero set is
/// polygonised with OpenVDB.

#include "core/csg_tree.h"
#include "core/run_control.h"
#include "core/triangle_mesh.h"

namespace csgvox {

/// Options of meshTree().
struct MeshOptions {
  int resolution = 160;          ///< voxels along the longest side of the tree's bounds, 8..2048
  double adaptivity = 0.0;       ///< 0: a quad per surface voxel; up to 1: fewer, larger triangles
  bool sharpenEdges = true;      ///< snap vertices to sharp edges and corners (adaptivity 0 only)
  double memoryLimitMiB = 4096;  ///< refuse when the estimated peak memory is larger, in MiB
};

/// Meshes the solid of `tree` (its FRep zero set, with the min/max set
/// operations). The result is closed (isClosed()), oriented outwards
/// (positive volume()) and has about 2 triangles per surface voxel; it is
/// empty when the bounded tree has no surface. With `sharpenEdges`, vertices
/// are placed on the solid's sharp edges and corners from the exact field, so
/// volume and area stay within about 0.1 % even at low resolutions; without
/// it (or with adaptivity > 0) every sharp edge is chamfered by about a voxel,
/// which costs about 1 % of the area of a box at the default resolution.
/// Assumes the field is 1-Lipschitz (true for the exact primitive distances
/// combined with min/max), which lets it skip voxels far from the surface and
/// evaluate only the primitives that can change the field near each part of
/// the surface (the tree is pruned over a hierarchy of lattice blocks), so
/// trees with many leaves mesh in about the time of their surface. The result
/// is the same as evaluating the whole tree everywhere.
/// Runs in parallel (TBB). `control`'s progress callback hears the stages
/// "cull", "sample", "polygonise" and "sharpen" (from worker threads, one
/// call at a time); a cancel request stops the meshing (it has no deadline).
/// @throw std::invalid_argument when the tree is empty or invalid, its bounds
///        are empty or unbounded (e.g. a bare half-space or a complement),
///        a primitive is too large to mesh (coordinates beyond 1e30) or the
///        solid too small for the resolution (voxels below 1.5e-5; the message
///        names the primitive), `resolution` is outside [8, 2048],
///        `adaptivity` outside [0, 1], or the estimated memory exceeds
///        `memoryLimitMiB`; CancelledError when `control` was cancelled.
TriangleMesh meshTree(const CsgTree& tree, const MeshOptions& options = {},
                      const RunControl& control = {});

}  // namespace csgvox
