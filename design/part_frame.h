#pragma once
/// The part's frame: orthonormal axes chosen from the directions the tree's
/// primitives share (cylinder axes first, then box axes and plane normals),
/// with its origin at a datum (the main axis, or the corner of the part's
/// bounds). Every designed value is a coordinate in this frame; the outputs
/// carry one placement (frame to world) at their top.

#include <span>

#include "core/csg_tree.h"

namespace csgvox {

/// A rigid placement: world = rotation · local + origin.
struct PartFrame {
  Mat3 rotation = Mat3::Identity();  ///< columns: the frame's x, y, z axes in world coordinates
  Vec3 origin = Vec3::Zero();        ///< the frame's origin in world coordinates
  bool spinFree =
      false;  ///< no face of the part fixes x (a turned part): any turn about z is as good

  /// World coordinates of a point given in the frame.
  Vec3 toWorld(const Vec3& local) const { return rotation * local + origin; }
  /// Frame coordinates of a world point.
  Vec3 toLocal(const Vec3& world) const { return rotation.transpose() * (world - origin); }
  /// True when the frame is the world's own (no placement to write).
  bool isIdentity() const { return rotation == Mat3::Identity() && origin == Vec3::Zero(); }
  /// The placement as rotation angles about x, then y, then z (degrees,
  /// OpenSCAD's rotate([a, b, c]) order): rotation = Rz(c)·Ry(b)·Rx(a).
  Vec3 eulerDegrees() const;
};

/// Options of partFrame().
struct FrameOptions {
  double parallelTolerance = 1e-3;  ///< directions this close to parallel vote together, radians
  double worldTolerance = 1e-6;     ///< a frame this close to the world axes becomes them, radians
  double originTolerance = 1e-6;    ///< origin coordinates this close to a whole unit (half,
                                    ///< tenth, hundredth) become it, fraction of the diagonal
};

/// The frame of `tree`. Directions vote with the number of `points` (scan
/// points, world coordinates) lying on the faces they orient, or with the
/// faces' areas when `points` is empty; z is the heaviest cylinder, cone or
/// torus axis (the heaviest direction when there is none), x the direction
/// orthogonal to it, of those with at least 5 % of the votes, along which
/// the part is longest (else free: spinFree). Signs put the solid's centroid on the low side
/// of z and x. A rotated copy of a tree gives the rotated frame (up to the
/// signs of a symmetric part's axes, which give the same values).
/// @throw std::invalid_argument for an empty tree.
PartFrame partFrame(const CsgTree& tree, std::span<const Vec3> points = {},
                    const FrameOptions& options = {});

/// `origin` with each coordinate within `tolerance` (scan units) of a whole
/// unit, half, tenth or hundredth set to it.
Vec3 roundedOrigin(Vec3 origin, double tolerance);

/// The signed permutation of the world axes nearest `rotation` (a
/// right-handed one) when each of its columns lies within `tolerance`
/// radians of a world axis; else `rotation` itself.
Mat3 nearestWorldAxes(const Mat3& rotation, double tolerance);

/// `primitive` moved by world = rotation · p + translation.
Primitive transformedPrimitive(const Primitive& primitive, const Mat3& rotation,
                               const Vec3& translation);
/// `tree` with every primitive moved by world = rotation · p + translation
/// (leaf names kept; a shared leaf stays shared).
CsgTree transformedTree(const CsgTree& tree, const Mat3& rotation, const Vec3& translation);
/// `tree` (world coordinates) in the frame's coordinates.
CsgTree treeInFrame(const CsgTree& tree, const PartFrame& frame);
/// `tree` (frame coordinates) in world coordinates.
CsgTree treeInWorld(const CsgTree& tree, const PartFrame& frame);

}  // namespace csgvox
