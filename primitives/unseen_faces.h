#pragma once
/// Faces the scanner never saw, closed for the labels. A part scanned in one
/// setup stands on a face that no view sees: the scan is an open shell, and
/// near that face the winding number of its points reads about 0.5, so the
/// labels there fall to either side by the noise (a block under a hub loses
/// its lower half where its top is open too). That face lies on the convex
/// hull of the points, nothing was seen on it, and its boundary was seen: the
/// lowest points of the walls standing on it. Samples of such a planar region
/// of the hull where no point lies near are tested by rays cast into the
/// hull: where every ray meets a face of the scan from behind first (its
/// outward normal along the ray: the sample is in the material), the sample
/// is on a face never seen and gives points with the hull's outward normal.
/// Where a ray meets a face from the front (the floor or wall of a slot, a
/// bore or a cup: the sample is in the air of its mouth) or none (it leaves
/// through an opening), the sample is left open, so a hole through the
/// unseen face stays open; a hull region that bridges air (between a
/// table's feet, under a bracket's overhang) is not closed at all.

#include <cstddef>

#include "core/point_cloud.h"

namespace csgvox {

/// Options of unseenHullFaces.
struct UnseenFaceOptions {
  bool enabled = true;  ///< false: no points added
  /// A hull sample is unseen when no scan point lies within this many of
  /// the scan's median spacings (ratio).
  double clearance = 2.5;
  /// A planar region of the hull (facets within 2 degrees) is closed only
  /// when at least this share of its boundary lies within the clearance of
  /// a scan point (ratio): the face a part stood on is bounded by its walls'
  /// lowest points all around; a hull facet that bridges a concavity spans
  /// air.
  double minBoundarySeen = 0.35;
  /// ... and when at least this share of its lattice samples is unseen
  /// (ratio): on a face no view saw nothing was seen but its walls' lowest
  /// points; a seen face is unseen only in gaps of the sampling and in the
  /// mouths of its holes (at most 0.45 of a region on the bundled scans).
  double minUnseenShare = 0.5;
  /// Of a closable region's unseen samples, those that must be kept (in the
  /// material, as below) for any to be: at least this many (count) and this
  /// share of them (ratio). A face no view saw is material over much of it;
  /// a region over air (a mouth, a facet bridging a concavity) holds a
  /// stray sample near its rim at most (1 in 180 on the bundled scans).
  int minKept = 2;
  double minKeptShare = 0.01;
  /// A ray meets the scan where a point lies within this many median
  /// spacings of it (ratio).
  double hitRadius = 1.5;
  /// A face met from behind with a face met from the front within this many
  /// median spacings before it, both within as many of the ray, is a wall
  /// thinner than that, entered from the front (ratio): a face seen at a
  /// grazing angle or through a mouth (a tray's floor) is sampled more
  /// sparsely than the median, and a ray can slip through a gap in it to
  /// the dense face behind.
  double thinWall = 3.0;
  /// Points whose normals make a smaller |cosine| with the ray are grazed,
  /// not met (a wall along the ray).
  double grazing = 0.3;
  /// Tilt of the four side rays from the inward hull normal (radians, 35
  /// degrees): from the mouth of a cup whose floor no view saw they meet its
  /// wall where a view at the scanner's elevations saw it, from the front.
  double tilt = 0.6108652381980153;
  /// Of the five rays, those that must meet a face from behind, none from
  /// the front (count): all, since a ray that leaves through an opening (a
  /// window of a frame, a bore) shows the sample is in air.
  int minBackHits = 5;
};

/// What unseenHullFaces found.
struct UnseenFaces {
  PointCloud points;       ///< samples of faces never seen, with outward normals
  std::size_t tested = 0;  ///< hull samples (2 step apart) with no scan point near (count)
  double area = 0.0;       ///< area the points cover (scan units squared)
};

/// Points on the faces of the convex hull of `scan` (oriented normals
/// required) that no view saw, as the header comment says: the rays are cast
/// from a lattice 2 `step` apart in each planar region's plane, and each
/// sample kept gives the four points `step` apart around it that have no
/// scan point near. Empty when the scan has fewer than 4 points, no normals,
/// or a flat hull. Deterministic with any number of threads and from run to
/// run, however CGAL triangulates a face of coplanar hull points.
UnseenFaces unseenHullFaces(const PointCloud& scan, double step,
                            const UnseenFaceOptions& options = {});

}  // namespace csgvox
