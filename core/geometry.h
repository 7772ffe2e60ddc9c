#pragma once
/// Basic geometric value types shared by every csgvox module.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>

namespace csgvox {

/// A point or direction in 3D, in the scan's own units.
using Vec3 = Eigen::Vector3d;
/// A 3x3 matrix; for frames, the columns are the frame's unit axes.
using Mat3 = Eigen::Matrix3d;

/// Axis-aligned bounding box. A default-constructed box is empty; a box may be
/// unbounded (infinite extents) when it bounds a half-space.
struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  /// The box of everything (an unbounded box).
  static Aabb everything();
  /// True when the box contains no point.
  bool isEmpty() const { return (min.array() > max.array()).any(); }
  /// True when the box is non-empty and every extent is finite.
  bool isBounded() const;
  /// Grows the box to contain p.
  void extend(const Vec3& p);
  /// Grows the box to contain other.
  void extend(const Aabb& other);
  /// The box grown by `margin` on every side (an empty box stays empty).
  Aabb grown(double margin) const {
    Aabb b = *this;
    if (!isEmpty()) {
      b.min.array() -= margin;
      b.max.array() += margin;
    }
    return b;
  }
  /// Intersection of two boxes (may be empty).
  Aabb intersected(const Aabb& other) const;
  /// Length of the diagonal (0 for an empty box, infinite for an unbounded one).
  double diagonal() const;
  Vec3 center() const { return 0.5 * (min + max); }
  Vec3 size() const { return max - min; }
  bool contains(const Vec3& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
};

/// A right-handed orthonormal frame whose third axis is `axis` (unit). The
/// other two axes are chosen deterministically from `axis` alone.
Mat3 frameFromAxis(const Vec3& axis);

}  // namespace csgvox
