#include "core/point_cloud.h"

namespace csgvox {

Aabb PointCloud::bounds() const {
  Aabb b;
  for (const Vec3& p : points) b.extend(p);
  return b;
}

}  // namespace csgvox
