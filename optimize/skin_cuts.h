#pragma once
/// Cuts that go through a skin thinner than voxels can see. A subtracted
/// primitive whose face stops just short of where the solid it cuts ends
/// leaves a sliver of material the voxels never saw (a hole that should go
/// through a shaft stops short of its curved surface, and a mesher or
/// OpenSCAD then renders a closed cavity). These routines push such a face
/// out through the skin, unless the skin's outer face holds scan points: a
/// scanned face there is a real wall thinner than a voxel (a sheet-metal
/// box), not an artefact.

#include <functional>
#include <span>

#include "core/csg_tree.h"
#include "core/geometry.h"

namespace csgvox {

/// True when the scan has a point near p.
using ScannedAt = std::function<bool(const Vec3& p)>;

/// True when more than half of `probes` have a scan point near them; false
/// without a `scannedAt` or without probes.
bool mostlyScanned(const ScannedAt& scannedAt, std::span<const Vec3> probes);

/// `tool` (a box to subtract from `root`) with every face that lies inside
/// the root's outer boundary and within `snap` (scan units) of it moved out
/// to 2 `snap` past it, except a face whose outer face on the boundary is
/// mostly scanned. The root's bounds are taken from its corners: exact for a
/// box root, the axis-aligned bounds otherwise. `tool` unchanged when it is
/// not a box, when snap <= 0 or when no face moves.
CsgTree throughCut(const CsgTree& tool, const CsgTree& root, double snap,
                   const ScannedAt& scannedAt);

/// `tool` (a box, cylinder or cone to subtract from `solid`) with every end
/// face whose whole area stops within `snap` (scan units) of where `solid`
/// ends along the face's normal moved one `snap` past the farthest such
/// exit (a cone runs on along its own slope), except a face whose skin's
/// outer face is mostly scanned. `tool` unchanged for other primitives, for
/// a tree that is not a single primitive, when snap <= 0 or when no face
/// moves.
CsgTree throughSkin(const CsgTree& tool, const CsgTree& solid, double snap,
                    const ScannedAt& scannedAt);

}  // namespace csgvox
