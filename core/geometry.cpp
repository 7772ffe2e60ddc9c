#include "core/geometry.h"

#include <cmath>

namespace csgvox {

Aabb Aabb::everything() {
  Aabb b;
  b.min = Vec3::Constant(-std::numeric_limits<double>::infinity());
  b.max = Vec3::Constant(std::numeric_limits<double>::infinity());
  return b;
}

bool Aabb::isBounded() const { return !isEmpty() && min.allFinite() && max.allFinite(); }

void Aabb::extend(const Vec3& p) {
  min = min.cwiseMin(p);
  max = max.cwiseMax(p);
}

void Aabb::extend(const Aabb& other) {
  if (other.isEmpty()) return;
  min = min.cwiseMin(other.min);
  max = max.cwiseMax(other.max);
}

Aabb Aabb::intersected(const Aabb& other) const {
  Aabb b;
  b.min = min.cwiseMax(other.min);
  b.max = max.cwiseMin(other.max);
  return b;
}

double Aabb::diagonal() const {
  if (isEmpty()) return 0.0;
  return (max - min).norm();
}

Mat3 frameFromAxis(const Vec3& axis) {
  const Vec3 w = axis.normalized();
  // The world axis least aligned with w (first one on ties) gives the first
  // frame axis, so that w = z yields the identity frame.
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(w[i]) < std::abs(w[k])) k = i;
  }
  const Vec3 helper = Vec3::Unit(k);
  const Vec3 u = (helper - helper.dot(w) * w).normalized();
  const Vec3 v = w.cross(u);
  Mat3 m;
  m.col(0) = u;
  m.col(1) = v;
  m.col(2) = w;
  return m;
}

}  // namespace csgvox
