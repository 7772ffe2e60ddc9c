#include "core/triangle_mesh.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>

namespace csgvox {

double TriangleMesh::volume() const {
  if (triangles.empty()) return 0.0;
  // Tetrahedra against the centre of the bounds keep the sum well conditioned
  // for meshes far from the origin.
  const Vec3 r = bounds().center();
  double sixVolume = 0.0;
  for (const auto& t : triangles) {
    const Vec3 a = vertices[t[0]] - r, b = vertices[t[1]] - r, c = vertices[t[2]] - r;
    sixVolume += a.dot(b.cross(c));
  }
  return sixVolume / 6.0;
}

double TriangleMesh::area() const {
  double twiceArea = 0.0;
  for (const auto& t : triangles) {
    const Vec3& a = vertices[t[0]];
    twiceArea += (vertices[t[1]] - a).cross(vertices[t[2]] - a).norm();
  }
  return 0.5 * twiceArea;
}

bool TriangleMesh::isClosed() const {
  // Each directed edge must occur exactly once and its reverse exactly once.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * triangles.size());
  const auto key = [](std::uint32_t from, std::uint32_t to) {
    return (std::uint64_t{from} << 32) | to;
  };
  for (const auto& t : triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return false;
    for (int i = 0; i < 3; ++i) edges.push_back(key(t[i], t[(i + 1) % 3]));
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
  for (const std::uint64_t e : edges) {
    const auto from = static_cast<std::uint32_t>(e >> 32);
    const auto to = static_cast<std::uint32_t>(e & 0xffffffffu);
    if (!std::binary_search(edges.begin(), edges.end(), key(to, from))) return false;
  }
  return true;
}

Aabb TriangleMesh::bounds() const {
  Aabb b;
  for (const Vec3& v : vertices) b.extend(v);
  return b;
}

}  // namespace csgvox
