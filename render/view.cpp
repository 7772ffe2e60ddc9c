#include "render/view.h"

#include <algorithm>
#include <stdexcept>

namespace csgvox {

PreviewView PreviewView::framing(const Aabb& bounds, int width, int height, double margin) {
  if (!bounds.isBounded() || bounds.isEmpty() || width < 1 || height < 1) {
    throw std::invalid_argument("a preview needs bounded, non-empty bounds and a panel");
  }
  PreviewView v;
  v.width = width;
  v.height = height;
  v.center = bounds.center();
  // From the front (-y), the right (+x) and above (+z), as a CAD program's
  // default axonometric view.
  v.toEye = Vec3(1.0, -1.25, 0.95).normalized();
  v.right = Vec3::UnitZ().cross(v.toEye).normalized();
  v.up = v.toEye.cross(v.right);
  double halfX = 0.0, halfY = 0.0;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? bounds.max.x() : bounds.min.x(),
                      (c & 2) ? bounds.max.y() : bounds.min.y(),
                      (c & 4) ? bounds.max.z() : bounds.min.z());
    halfX = std::max(halfX, std::abs((corner - v.center).dot(v.right)));
    halfY = std::max(halfY, std::abs((corner - v.center).dot(v.up)));
  }
  const double usable = 1.0 - 2.0 * margin;
  v.pixelSize = std::max({2.0 * halfX / (usable * width), 2.0 * halfY / (usable * height), 1e-300});
  v.reach = bounds.diagonal();
  return v;
}

Vec3 PreviewView::rayOrigin(double x, double y) const {
  return center + reach * toEye + (x + 0.5 - 0.5 * width) * pixelSize * right -
         (y + 0.5 - 0.5 * height) * pixelSize * up;
}

Vec3 PreviewView::project(const Vec3& p) const {
  const Vec3 d = p - center;
  return Vec3(d.dot(right) / pixelSize + 0.5 * width - 0.5,
              -d.dot(up) / pixelSize + 0.5 * height - 0.5, reach - d.dot(toEye));
}

}  // namespace csgvox
