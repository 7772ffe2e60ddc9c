#pragma once
/// An indexed triangle mesh (the flat structure at the edge of the mesher and
/// the mesh readers) with its measures.

#include <array>
#include <cstdint>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// A triangle soup over shared vertices, in the scan's units. Triangles are
/// counter-clockwise seen from outside, so that the normal
/// (b - a) x (c - a) points out of the solid.
struct TriangleMesh {
  std::vector<Vec3> vertices;                           ///< vertex positions
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< vertex indices, counter-clockwise

  /// Signed enclosed volume (divergence theorem); positive for a closed,
  /// outward-oriented mesh. Meaningful only when isClosed().
  double volume() const;
  /// Total area of the triangles.
  double area() const;
  /// True when every edge is shared by exactly two triangles that use it in
  /// opposite directions (a closed, consistently oriented surface). An empty
  /// mesh is closed.
  bool isClosed() const;
  /// Axis-aligned bounds of the vertices (empty for an empty mesh).
  Aabb bounds() const;
};

}  // namespace csgvox
