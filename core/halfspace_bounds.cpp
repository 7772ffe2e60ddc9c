#include "core/halfspace_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace csgvox {

Aabb halfSpaceIntersectionBounds(std::span<const HalfSpace> halfSpaces, const Aabb& box) {
  if (box.isEmpty()) return Aabb();
  if (halfSpaces.empty()) return box;
  // The polyhedron's vertices inside a box far larger than every finite
  // number in play; a vertex on that far box means "unbounded that way".
  double scale = 1.0;
  for (const HalfSpace& h : halfSpaces) scale = std::max(scale, std::abs(h.offset));
  for (int k = 0; k < 3; ++k) {
    if (std::isfinite(box.min[k])) scale = std::max(scale, std::abs(box.min[k]));
    if (std::isfinite(box.max[k])) scale = std::max(scale, std::abs(box.max[k]));
  }
  const double far = 1e6 * scale;
  std::vector<HalfSpace> planes(halfSpaces.begin(), halfSpaces.end());
  for (int k = 0; k < 3; ++k) {
    const Vec3 e = Vec3::Unit(k);
    planes.push_back({e, std::isfinite(box.max[k]) ? box.max[k] : far});
    planes.push_back({-e, std::isfinite(box.min[k]) ? -box.min[k] : far});
  }
  const double tolerance = 1e-9 * far;
  Aabb out;
  const std::size_t m = planes.size();
  for (std::size_t a = 0; a < m; ++a) {
    for (std::size_t b = a + 1; b < m; ++b) {
      const Vec3 ab = planes[a].normal.cross(planes[b].normal);
      if (ab.squaredNorm() < 1e-18) continue;
      for (std::size_t c = b + 1; c < m; ++c) {
        const double det = ab.dot(planes[c].normal);
        if (std::abs(det) < 1e-9) continue;
        // Cramer's rule for n_a·x = d_a, n_b·x = d_b, n_c·x = d_c.
        const Vec3 x =
            (planes[a].offset * planes[b].normal.cross(planes[c].normal) +
             planes[b].offset * planes[c].normal.cross(planes[a].normal) + planes[c].offset * ab) /
            det;
        bool inside = x.allFinite();
        for (std::size_t i = 0; i < m && inside; ++i) {
          inside = planes[i].normal.dot(x) <= planes[i].offset + tolerance;
        }
        if (inside) out.extend(x);
      }
    }
  }
  if (out.isEmpty()) return out;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Vertices carry rounding error: the bounds are widened by a relative
  // slack so that they stay conservative (a voxel centre on a face counts).
  const double slack = 1e-9 * scale;
  for (int k = 0; k < 3; ++k) {
    out.max[k] = out.max[k] >= 0.5 * far ? kInf : out.max[k] + slack;
    out.min[k] = out.min[k] <= -0.5 * far ? -kInf : out.min[k] - slack;
  }
  return out;
}

}  // namespace csgvox
