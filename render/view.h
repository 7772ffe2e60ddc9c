#pragma once
/// The three-quarter view of the preview: an orthographic camera looking
/// down at the part from the front, the right and above, framing its bounds.

#include "core/geometry.h"

namespace csgvox {

/// An orthographic view onto a width x height panel of pixels.
struct PreviewView {
  Vec3 center = Vec3::Zero();  ///< the point seen at the panel's centre
  Vec3 toEye = Vec3::UnitZ();  ///< unit vector from the scene towards the viewer
  Vec3 right = Vec3::UnitX();  ///< unit screen direction of increasing x
  Vec3 up = Vec3::UnitY();     ///< unit screen direction of decreasing y (pixel rows)
  double pixelSize = 1.0;      ///< scene units per pixel
  double reach = 1.0;          ///< rays start this far in front of `center`
  int width = 1;               ///< panel width, pixels
  int height = 1;              ///< panel height, pixels

  /// The view of `bounds` (non-empty, bounded) filling a panel of
  /// width x height pixels but for a margin of `margin` (fraction of the
  /// panel) on each side.
  static PreviewView framing(const Aabb& bounds, int width, int height, double margin = 0.06);

  /// Start of the ray through the centre of pixel (x, y); the ray runs
  /// along -toEye.
  Vec3 rayOrigin(double x, double y) const;
  /// The panel position (x, y, continuous pixels) of p, and its depth along
  /// the ray (larger is farther from the viewer).
  Vec3 project(const Vec3& p) const;
};

}  // namespace csgvox
