#pragma once
/// Oriented boxes: a centre, an orthonormal frame and half sizes.

#include <span>

#include "core/geometry.h"

namespace csgvox {

/// An oriented box: centre, unit axes (columns, right-handed) and half sizes.
struct OrientedBox {
  Vec3 center = Vec3::Zero();
  Mat3 axes = Mat3::Identity();
  Vec3 halfSize = Vec3::Zero();
};

/// The bounding box of points in a given orthonormal frame (columns), with
/// the axes ordered longest first and made right-handed.
OrientedBox boxAlong(std::span<const Vec3> points, const Mat3& frame);

}  // namespace csgvox
