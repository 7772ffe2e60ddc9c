#include "scanner/ray_caster.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace csgvox {

std::optional<std::pair<double, double>> rayBoxInterval(const Aabb& box, const Vec3& origin,
                                                        const Vec3& direction, double maxDistance) {
  if (box.isEmpty()) return std::nullopt;
  double enter = 0.0, exit = maxDistance;
  for (int k = 0; k < 3; ++k) {
    if (direction[k] == 0.0) {
      if (origin[k] < box.min[k] || origin[k] > box.max[k]) return std::nullopt;
      continue;
    }
    const double inv = 1.0 / direction[k];
    double t0 = (box.min[k] - origin[k]) * inv;
    double t1 = (box.max[k] - origin[k]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    exit = std::min(exit, t1);
    if (enter > exit) return std::nullopt;
  }
  return std::make_pair(enter, exit);
}

}  // namespace csgvox
