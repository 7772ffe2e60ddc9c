// Bounding boxes of points in a given frame.

#include "core/oriented_box.h"

#include <algorithm>
#include <array>

namespace csgvox {

OrientedBox boxAlong(std::span<const Vec3> points, const Mat3& frame) {
  const Mat3& axes = frame;
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& p : points) {
    const Vec3 q = axes.transpose() * p;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  Vec3 half = 0.5 * (hi - lo);
  const Vec3 mid = 0.5 * (hi + lo);
  // Order the axes longest first, keep the frame right-handed.
  std::array<int, 3> order{0, 1, 2};
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return half[a] > half[b]; });
  OrientedBox box;
  for (int i = 0; i < 3; ++i) {
    box.axes.col(i) = axes.col(order[i]);
    box.halfSize[i] = half[order[i]];
  }
  if (box.axes.determinant() < 0.0) box.axes.col(2) = -box.axes.col(2);
  box.center = axes * mid;
  return box;
}

}  // namespace csgvox
