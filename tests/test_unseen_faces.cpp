// Faces never seen, closed for the labels (primitives/unseen_faces.h): the
// face a block stood on is covered, a fully seen block gains nothing, nor
// does a gap in the sampling of a seen face; the mouths of a bore through
// the unseen face and of a cup whose floor no view saw stay open, and so do
// the air under a table and a tray whose floor was seen sparsely.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "primitives/unseen_faces.h"

namespace csgvox {
namespace {

constexpr double kSpacing = 0.4;

// Points `spacing` apart on the rectangle corner + [0, a] u + [0, b] v with
// outward normal n, except where `skip` says.
void face(PointCloud& cloud, const Vec3& corner, const Vec3& u, double a, const Vec3& v, double b,
          const Vec3& n, const std::function<bool(const Vec3&)>& skip = {},
          double spacing = kSpacing) {
  for (double s = 0.5 * spacing; s < a; s += spacing) {
    for (double t = 0.5 * spacing; t < b; t += spacing) {
      const Vec3 p = corner + s * u + t * v;
      if (skip && skip(p)) continue;
      cloud.points.push_back(p);
      cloud.normals.push_back(n);
    }
  }
}

// Points on the wall of radius r about the z axis, z in [z0, z1], normals
// towards the axis (a bore).
void boreWall(PointCloud& cloud, double r, double z0, double z1) {
  const int around = int(2.0 * std::numbers::pi * r / kSpacing);
  for (double z = z0 + 0.5 * kSpacing; z < z1; z += kSpacing) {
    for (int k = 0; k < around; ++k) {
      const double a = 2.0 * std::numbers::pi * k / around;
      const Vec3 radial(std::cos(a), std::sin(a), 0.0);
      cloud.points.push_back(r * radial + Vec3(0, 0, z));
      cloud.normals.push_back(-radial);
    }
  }
}

// The block [-10, 10]^2 x [0, 10]: its four sides and top (each skipping
// where `hole` says), and its bottom when `bottom`.
PointCloud block(bool bottom, const std::function<bool(const Vec3&)>& hole = {}) {
  PointCloud c;
  const Vec3 x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
  face(c, Vec3(-10, -10, 10), x, 20, y, 20, z, hole);
  if (bottom) face(c, Vec3(-10, -10, 0), x, 20, y, 20, -z, hole);
  face(c, Vec3(-10, -10, 0), x, 20, z, 10, -y);
  face(c, Vec3(-10, 10, 0), x, 20, z, 10, y);
  face(c, Vec3(-10, -10, 0), y, 20, z, 10, -x);
  face(c, Vec3(10, -10, 0), y, 20, z, 10, x);
  return c;
}

TEST(UnseenFaces, TheFaceABlockStoodOnIsCovered) {
  const UnseenFaces u = unseenHullFaces(block(false), 0.25);
  ASSERT_GT(u.points.size(), 0u);
  ASSERT_TRUE(u.points.hasNormals());
  for (std::size_t i = 0; i < u.points.size(); ++i) {
    EXPECT_NEAR(u.points.points[i].z(), 0.5 * kSpacing, 1e-9);  // the lowest points
    EXPECT_NEAR(u.points.normals[i].z(), -1.0, 1e-9);
  }
  // Each point once: the bottom's hull facets, triangles of coplanar points,
  // share edges that lattice points lie on.
  std::vector<std::array<double, 3>> at;
  for (const Vec3& p : u.points.points) at.push_back({p.x(), p.y(), p.z()});
  std::sort(at.begin(), at.end());
  EXPECT_EQ(std::adjacent_find(at.begin(), at.end()), at.end());
  // All of the bottom but a rim of the clearance (2.5 spacings) about its edges.
  const double covered = 20.0 - 2.0 * 2.5 * kSpacing;
  EXPECT_GT(u.area, 0.9 * covered * covered);
  EXPECT_LT(u.area, 1.05 * 20.0 * 20.0);
}

// A disc of radius r at height z (points about `kSpacing` apart), normal n.
void disc(PointCloud& cloud, double r, double z, const Vec3& n) {
  for (double x = -r; x <= r; x += kSpacing) {
    for (double y = -r; y <= r; y += kSpacing) {
      if (x * x + y * y > r * r) continue;
      cloud.points.push_back(Vec3(x, y, z));
      cloud.normals.push_back(n);
    }
  }
}

// A fully seen cylinder, radius 15: its hull's side facets, 1.5 degrees apart,
// chain into one region around the axis, whose mean normal says nothing of
// them; each facet's lattice points are taken on its own plane.
TEST(UnseenFaces, AFullySeenCylinderGainsNothing) {
  PointCloud c;
  const double r = 15.0;
  const int around = int(2.0 * std::numbers::pi * r / kSpacing);
  for (double z = 0.5 * kSpacing; z < 10.0; z += kSpacing) {
    for (int k = 0; k < around; ++k) {
      const double a = 2.0 * std::numbers::pi * k / around;
      const Vec3 radial(std::cos(a), std::sin(a), 0.0);
      c.points.push_back(r * radial + Vec3(0, 0, z));
      c.normals.push_back(radial);
    }
  }
  disc(c, r - 0.5 * kSpacing, 0.0, -Vec3::UnitZ());
  disc(c, r - 0.5 * kSpacing, 10.0, Vec3::UnitZ());
  const UnseenFaces u = unseenHullFaces(c, 0.25);
  EXPECT_EQ(u.points.size(), 0u);
}

TEST(UnseenFaces, AFullySeenBlockGainsNothing) {
  const UnseenFaces u = unseenHullFaces(block(true), 0.25);
  EXPECT_EQ(u.points.size(), 0u);
  EXPECT_EQ(u.tested, 0u);
}

TEST(UnseenFaces, ABoreThroughTheUnseenFaceStaysOpen) {
  // A bore of radius 3 through the block, its wall seen down to z = 4 only.
  const auto inBore = [](const Vec3& p) { return p.head<2>().norm() < 3.0; };
  PointCloud c = block(false, inBore);
  boreWall(c, 3.0, 4.0, 10.0);
  const UnseenFaces u = unseenHullFaces(c, 0.25);
  ASSERT_GT(u.points.size(), 0u);
  for (const Vec3& p : u.points.points) EXPECT_GT(p.head<2>().norm(), 3.0) << p.transpose();
  EXPECT_GT(u.area, 0.8 * (20.0 - 2.0) * (20.0 - 2.0) - std::numbers::pi * 9.0 * 2.0);
}

TEST(UnseenFaces, TheMouthOfACupWhoseFloorNoViewSawStaysOpen) {
  // Every face seen, the bottom included, but a round pocket of radius 3
  // from the top, 9 deep, whose wall a view at 55 degrees of elevation saw
  // down to z = 2 and whose floor no view saw: rays from its mouth meet its
  // wall from the front.
  // The top is seen but for the mouth, so the rays are asked only when
  // a region need not be mostly unseen.
  const auto inCup = [](const Vec3& p) { return p.z() > 1.0 && p.head<2>().norm() < 3.0; };
  PointCloud c = block(true, inCup);
  boreWall(c, 3.0, 2.0, 10.0);
  UnseenFaceOptions anyShare;
  anyShare.minUnseenShare = 0.0;
  const UnseenFaces u = unseenHullFaces(c, 0.25, anyShare);
  EXPECT_EQ(u.points.size(), 0u);
  EXPECT_GT(u.tested, 0u);
}

TEST(UnseenFaces, AGapInTheSamplingOfASeenFaceStaysOpen) {
  // Every face seen, but a disc of radius 1.5 of the top without points:
  // rays from it go through the block and meet its bottom from behind, as
  // from a face no view saw; but the top is seen nearly everywhere else.
  const auto inGap = [](const Vec3& p) {
    return p.z() > 5.0 && (p.head<2>() - Eigen::Vector2d(4.0, 3.0)).norm() < 1.5;
  };
  const PointCloud c = block(true, inGap);
  const UnseenFaces u = unseenHullFaces(c, 0.25);
  EXPECT_GT(u.tested, 0u);
  EXPECT_EQ(u.points.size(), 0u);
  UnseenFaceOptions anyShare;
  anyShare.minUnseenShare = 0.0;
  EXPECT_GT(unseenHullFaces(c, 0.25, anyShare).points.size(), 0u);  // what the test guards
}

TEST(UnseenFaces, TooFewSamplesKeptInARegionCloseNothing) {
  // The face the block stood on keeps every sample the clearance leaves;
  // asking for more than it has, or for more than all of its unseen
  // samples, closes nothing.
  const PointCloud c = block(false);
  const UnseenFaces all = unseenHullFaces(c, 0.25);
  ASSERT_GT(all.points.size(), 0u);
  UnseenFaceOptions count;
  count.minKept = int(all.points.size());  // 4 points per kept sample
  EXPECT_EQ(unseenHullFaces(c, 0.25, count).points.size(), 0u);
  UnseenFaceOptions share;
  share.minKeptShare = 1.01;
  EXPECT_EQ(unseenHullFaces(c, 0.25, share).points.size(), 0u);
}

// The four vertical sides of the box [lo, hi], outward normals.
void sides(PointCloud& c, const Vec3& lo, const Vec3& hi) {
  const Vec3 x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
  const Vec3 d = hi - lo;
  face(c, lo, x, d.x(), z, d.z(), -y);
  face(c, Vec3(lo.x(), hi.y(), lo.z()), x, d.x(), z, d.z(), y);
  face(c, lo, y, d.y(), z, d.z(), -x);
  face(c, Vec3(hi.x(), lo.y(), lo.z()), y, d.y(), z, d.z(), x);
}

TEST(UnseenFaces, ATableOnFourLegsIsNotClosedUnderneath) {
  // A top [-10, 10]^2 x [8, 10] on four legs 2 x 2 at its corners, scanned
  // standing: the top's underside and the feet are never seen. Rays from
  // under its middle pass that underside and leave through the top from
  // behind, as from a face the table stood on; but the hull's face there
  // bridges air between the feet: its boundary was seen only at them.
  PointCloud c;
  face(c, Vec3(-10, -10, 10), Vec3::UnitX(), 20, Vec3::UnitY(), 20, Vec3::UnitZ());
  sides(c, Vec3(-10, -10, 8), Vec3(10, 10, 10));
  for (const double x : {-10.0, 8.0}) {
    for (const double y : {-10.0, 8.0}) sides(c, Vec3(x, y, 0), Vec3(x + 2, y + 2, 8));
  }
  EXPECT_EQ(unseenHullFaces(c, 0.25).points.size(), 0u);
  UnseenFaceOptions anyBoundary;
  anyBoundary.minBoundarySeen = 0.0;
  EXPECT_GT(unseenHullFaces(c, 0.25, anyBoundary).points.size(), 0u);  // what the test guards
}

TEST(UnseenFaces, TheMouthOfATrayWhoseFloorWasSeenSparselyStaysOpen) {
  // A tray [-10, 10]^2 x [0, 10] with walls and a floor 1 thick, every face
  // seen, but the floor's top only through the mouth, at five times the
  // spacing: rays from the mouth slip through its gaps to the floor's dense
  // underside, which they meet from behind; the top just before it shows
  // they entered a thin wall from the front.
  const Vec3 x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
  PointCloud c;
  face(c, Vec3(-10, -10, 0), x, 20, y, 20, -z);
  face(c, Vec3(-9, -9, 1), x, 18, y, 18, z, {}, 5.0 * kSpacing);
  sides(c, Vec3(-10, -10, 0), Vec3(10, 10, 10));
  const auto inMouth = [](const Vec3& p) { return std::abs(p.x()) < 9.0 && std::abs(p.y()) < 9.0; };
  face(c, Vec3(-10, -10, 10), x, 20, y, 20, z, inMouth);
  // The inner walls, facing into the tray.
  face(c, Vec3(-9, -9, 1), x, 18, z, 9, y);
  face(c, Vec3(-9, 9, 1), x, 18, z, 9, -y);
  face(c, Vec3(-9, -9, 1), y, 18, z, 9, x);
  face(c, Vec3(9, -9, 1), y, 18, z, 9, -x);
  EXPECT_EQ(unseenHullFaces(c, 0.25).points.size(), 0u);
  UnseenFaceOptions noThinWalls;
  noThinWalls.thinWall = 0.0;
  EXPECT_GT(unseenHullFaces(c, 0.25, noThinWalls).points.size(), 0u);  // what the test guards
}

TEST(UnseenFaces, DisabledOrWithoutNormalsAddsNothing) {
  UnseenFaceOptions off;
  off.enabled = false;
  EXPECT_EQ(unseenHullFaces(block(false), 0.25, off).points.size(), 0u);
  PointCloud bare = block(false);
  bare.normals.clear();
  EXPECT_EQ(unseenHullFaces(bare, 0.25).points.size(), 0u);
}

}  // namespace
}  // namespace csgvox
