// Labels completed by the bores the detection saw (voxel/seen_bores.h): a
// bore seen near its ends is opened along its length, a branch seen near its
// mouth is opened into the run's bore, a hole through a face never seen to
// the outside or down to a plane across it, and nothing is opened where
// points show material across a bore or close its far end.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "voxel/seen_bores.h"

namespace csgvox {
namespace {

// Voxels of 1 mm over [-20, 20] x [-20, 20] x [-40, 40].
VoxelGrid testGrid() { return VoxelGrid(Vec3(-20, -20, -40), Mat3::Identity(), 1.0, {40, 40, 80}); }

VoxelSet labelsWhere(const VoxelGrid& grid, const std::function<bool(const Vec3&)>& in) {
  VoxelSet set(grid.voxelCount());
  for (std::size_t v = 0; v < grid.voxelCount(); ++v) {
    if (in(grid.center(v))) set.set(v);
  }
  return set;
}

struct Scene {
  PointCloud cloud;
  std::vector<Surface> surfaces;
  std::mt19937 rng{7};

  // `count` points on the wall of radius r about the axis through `point`
  // along the unit `axis`, between depths t0 and t1, over the angles
  // [0, sweep); with `asSurface` they are the inliers of a concave (hole)
  // cylinder, else loose points with outward normals (a boss).
  void wall(const Vec3& point, const Vec3& axis, double r, double t0, double t1, int count,
            bool asSurface, double sweep = 2.0 * std::numbers::pi) {
    const Mat3 f = frameFromAxis(axis);
    std::uniform_real_distribution<double> angle(0.0, sweep), depth(t0, t1);
    Surface s;
    s.shape = CylinderSurface{point, axis, r};
    s.convex = !asSurface;
    for (int k = 0; k < count; ++k) {
      const double a = angle(rng);
      const Vec3 radial = std::cos(a) * f.col(0) + std::sin(a) * f.col(1);
      s.inliers.push_back(std::uint32_t(cloud.size()));
      cloud.points.push_back(point + depth(rng) * axis + r * radial);
      cloud.normals.push_back(asSurface ? Vec3(-radial) : radial);
    }
    if (asSurface) surfaces.push_back(std::move(s));
  }

  // The last two walls' inliers as one surface (one wall seen in two
  // stretches).
  void joinLastTwo() {
    Surface last = std::move(surfaces.back());
    surfaces.pop_back();
    std::vector<std::uint32_t>& into = surfaces.back().inliers;
    into.insert(into.end(), last.inliers.begin(), last.inliers.end());
  }

  // `count` points on the disc of radius r about `centre`, normal n.
  void disc(const Vec3& centre, const Vec3& n, double r, int count) {
    const Mat3 f = frameFromAxis(n);
    std::uniform_real_distribution<double> u(-r, r);
    for (int k = 0; k < count;) {
      const double a = u(rng), b = u(rng);
      if (a * a + b * b > r * r) continue;
      cloud.points.push_back(centre + a * f.col(0) + b * f.col(1));
      cloud.normals.push_back(n);
      ++k;
    }
  }
};

TEST(SeenBores, ABoreSeenNearItsEndsIsOpenedAlongItsLength) {
  const VoxelGrid grid = testGrid();
  // A pipe along z: outer radius 15, bore 8, z in [-30, 30]; the labels fill
  // the bore where its wall is unseen, between z = -22 and 22 (the winding
  // number of the points gets the seen stretches right).
  const auto solid = [](const Vec3& p) {
    return std::abs(p.z()) < 30.0 && p.head<2>().norm() < 15.0;
  };
  VoxelSet inside = labelsWhere(grid, [&](const Vec3& p) {
    return solid(p) && (p.head<2>().norm() > 8.0 || std::abs(p.z()) < 22.0);
  });
  Scene scene;
  scene.wall(Vec3::Zero(), Vec3::UnitZ(), 8.0, -30.0, -22.0, 600, true);
  scene.wall(Vec3::Zero(), Vec3::UnitZ(), 8.0, 22.0, 30.0, 600, true);
  // The same wall as one surface, and a few stray points in the bore.
  scene.joinLastTwo();
  scene.disc(Vec3(0, 0, 5), Vec3::UnitZ(), 5.0, 3);

  const BoreOpening done = openSeenBores(grid, scene.cloud, scene.surfaces, inside);
  EXPECT_EQ(done.bores, 1u);
  EXPECT_EQ(done.extended, 0u);
  std::size_t wrongIn = 0, wrongOut = 0;
  for (std::size_t v = 0; v < grid.voxelCount(); ++v) {
    const Vec3 c = grid.center(v);
    const bool truth = solid(c) && c.head<2>().norm() > 8.0;
    wrongIn += !truth && inside.test(v);
    wrongOut += truth && !inside.test(v);
  }
  EXPECT_EQ(wrongOut, 0u);
  // The bore's voxels are outside along the whole pipe (its inliers span
  // z = -30 to 30 to within their sampling).
  EXPECT_LT(wrongIn, 60u);
  EXPECT_GT(done.voxels, 7000u);  // ~ pi 8^2 x 44 = 8 850 voxels
}

TEST(SeenBores, ASmallHoleSeenAtItsEndsIsOpened) {
  const VoxelGrid grid = testGrid();
  // A through hole of radius 1.6 voxels (3.2 wide: about 8 voxel centres
  // in each slab across it) in a block z in [-30, 30]; its wall is seen in
  // the last 4 at either end, and the labels fill the rest. It opens along
  // its length; below 1.5 voxels in radius nothing is opened.
  const auto solid = [](const Vec3& p) {
    return std::abs(p.z()) < 30.0 && std::abs(p.x()) < 15.0 && std::abs(p.y()) < 15.0;
  };
  const Vec3 axis(0.5, 0.5, 0.0);  // off the voxel centres' lattice by half a voxel
  const double r = 1.6;
  const auto inHole = [&](const Vec3& p) { return (p - axis).head<2>().norm() < r; };
  const auto labels = [&] {
    return labelsWhere(
        grid, [&](const Vec3& p) { return solid(p) && (!inHole(p) || std::abs(p.z()) < 26.0); });
  };
  Scene scene;
  scene.wall(axis, Vec3::UnitZ(), r, -30.0, -26.0, 120, true);
  scene.wall(axis, Vec3::UnitZ(), r, 26.0, 30.0, 120, true);
  scene.joinLastTwo();
  VoxelSet inside = labels();
  const BoreOpening done = openSeenBores(grid, scene.cloud, scene.surfaces, inside);
  EXPECT_EQ(done.bores, 1u);
  std::size_t filled = 0;
  for (std::size_t v = 0; v < grid.voxelCount(); ++v) {
    const Vec3 c = grid.center(v);
    EXPECT_EQ(inside.test(v), solid(c) && !inHole(c)) << c.transpose();
    filled += inHole(c) && std::abs(c.z()) < 26.0 ? 1 : 0;
  }
  EXPECT_EQ(done.voxels, filled);
  EXPECT_GT(filled, 7u * 50u);
  BoreOpeningOptions larger;
  larger.minRadiusVoxels = 1.7;
  VoxelSet unopened = labels();
  EXPECT_EQ(openSeenBores(grid, scene.cloud, scene.surfaces, unopened, larger).bores, 0u);
  EXPECT_EQ(unopened, labels());
}

TEST(SeenBores, ABoreSeenAlongItsWholeLengthIsLeftToThePoints) {
  const VoxelGrid grid = testGrid();
  // The same pipe with its bore's wall seen all along: a few inside voxels
  // in the bore (a ring next to the wall, as noise gives) stay as labelled.
  VoxelSet inside = labelsWhere(grid, [](const Vec3& p) {
    const double rho = p.head<2>().norm();
    return std::abs(p.z()) < 30.0 && rho < 15.0 && (rho > 7.0 || std::abs(p.z()) < 2.0);
  });
  Scene scene;
  scene.wall(Vec3::Zero(), Vec3::UnitZ(), 8.0, -30.0, 30.0, 4000, true);
  const VoxelSet before = inside;
  const BoreOpening done = openSeenBores(grid, scene.cloud, scene.surfaces, inside);
  EXPECT_EQ(done.bores, 1u);
  EXPECT_EQ(done.voxels, 0u);
  EXPECT_EQ(inside, before);
}

TEST(SeenBores, ABossStandingInARoundPocketStaysInside) {
  const VoxelGrid grid = testGrid();
  // A round pocket of radius 10, z in [0, 10], its wall seen near the mouth
  // only, with a boss of radius 4 standing in it; the labels wrongly fill
  // the pocket around the boss below the seen stretch.
  VoxelSet inside = labelsWhere(grid, [](const Vec3& p) {
    return p.z() > -20 && (p.z() < 7.0 || (p.z() < 10.0 && p.head<2>().norm() > 10.0));
  });
  Scene scene;
  scene.wall(Vec3::Zero(), Vec3::UnitZ(), 10.0, 0.0, 0.5, 100, true);
  scene.wall(Vec3::Zero(), Vec3::UnitZ(), 10.0, 7.0, 10.0, 500, true);
  scene.joinLastTwo();
  scene.wall(Vec3::Zero(), Vec3::UnitZ(), 4.0, 0.0, 10.0, 600, false);
  const VoxelSet before = inside;
  const BoreOpening done = openSeenBores(grid, scene.cloud, scene.surfaces, inside);
  EXPECT_EQ(done.bores, 1u);
  EXPECT_EQ(done.voxels, 0u);
  EXPECT_EQ(inside, before);
}

// A block z in [-30, 30] with a hole of radius 6 seen from its mouth at
// z = 30 down to z = 20, its floor unseen; the labels have the seen stretch
// right and the rest of the block inside.
struct DeepHole {
  VoxelGrid grid = testGrid();
  Scene scene;
  VoxelSet inside;
  DeepHole() {
    inside = labelsWhere(grid, [](const Vec3& p) {
      return std::abs(p.z()) < 30.0 && (p.z() < 20.0 || p.head<2>().norm() > 6.0);
    });
    scene.wall(Vec3::Zero(), Vec3::UnitZ(), 6.0, 20.0, 30.0, 800, true);
  }
  // Inside labels of the hole's axis region: below z (true) or above it.
  void expectHoleOpenDownTo(double z) const {
    for (std::size_t v = 0; v < grid.voxelCount(); ++v) {
      const Vec3 c = grid.center(v);
      if (c.head<2>().norm() >= 5.5 || std::abs(c.z()) > 30.0) continue;
      if (c.z() > z + 0.5) {
        EXPECT_FALSE(inside.test(v)) << c.transpose();
      } else if (c.z() < z - 0.5) {
        EXPECT_TRUE(inside.test(v)) << c.transpose();
      }
    }
  }
};

TEST(SeenBores, AHoleWhoseFarFaceIsSeenClosedEndsWhereItWasSeen) {
  // The block's bottom face seen under the hole: the hole is blind, its
  // floor somewhere unseen; the labels are left as the points give them.
  DeepHole hole;
  hole.scene.disc(Vec3(0, 0, -30), -Vec3::UnitZ(), 6.0, 150);
  const BoreOpening done =
      openSeenBores(hole.grid, hole.scene.cloud, hole.scene.surfaces, hole.inside);
  EXPECT_EQ(done.bores, 1u);
  EXPECT_EQ(done.extended, 0u);
  EXPECT_EQ(done.voxels, 0u);
  hole.expectHoleOpenDownTo(20.0);
}

TEST(SeenBores, AHoleThroughAFaceNeverSeenIsOpenedToTheOutside) {
  // Nothing seen below the hole (the face the part stood on): the labels
  // close that face only where it is material, so past the block is the
  // outside, and the hole goes through.
  DeepHole hole;
  const BoreOpening done =
      openSeenBores(hole.grid, hole.scene.cloud, hole.scene.surfaces, hole.inside);
  EXPECT_EQ(done.bores, 1u);
  EXPECT_EQ(done.extended, 1u);
  hole.expectHoleOpenDownTo(-31.0);
}

TEST(SeenBores, AHoleEndsAtAPlaneAcrossItsAxis) {
  // A face of the part at z = 5 facing up (the top of a step the hole's
  // boss stands on): the hole's floor is taken there.
  DeepHole hole;
  Surface step;
  step.shape = PlaneSurface{Vec3::UnitZ(), 5.0};
  hole.scene.surfaces.push_back(step);
  // A plane across the axis facing down is no floor of a hole from above.
  Surface under;
  under.shape = PlaneSurface{-Vec3::UnitZ(), -10.0};
  hole.scene.surfaces.push_back(under);
  const BoreOpening done =
      openSeenBores(hole.grid, hole.scene.cloud, hole.scene.surfaces, hole.inside);
  EXPECT_EQ(done.extended, 0u);
  EXPECT_GT(done.voxels, 0u);
  hole.expectHoleOpenDownTo(5.0);
}

// A tee: a run bore of radius 8 along x (seen near both ends) and a branch
// bore of radius 5 along z from the top, seen only near its mouth.
struct Tee {
  VoxelGrid grid = testGrid();
  Scene scene;
  VoxelSet inside;
  static bool solid(const Vec3& p) {
    const bool run = std::abs(p.x()) < 19.0 && p.tail<2>().norm() < 12.0;
    const bool branch = p.z() > 0.0 && p.z() < 30.0 && p.head<2>().norm() < 9.0;
    return run || branch;
  }
  Tee() {
    inside = labelsWhere(grid, solid);
    scene.wall(Vec3::Zero(), Vec3::UnitX(), 8.0, -19.0, -13.0, 500, true);
    scene.wall(Vec3::Zero(), Vec3::UnitX(), 8.0, 13.0, 19.0, 500, true);
    scene.joinLastTwo();
    scene.wall(Vec3::Zero(), Vec3::UnitZ(), 5.0, 22.0, 30.0, 500, true);
  }
};

TEST(SeenBores, ABranchSeenNearItsMouthIsOpenedIntoTheRunsBore) {
  Tee tee;
  const BoreOpening done = openSeenBores(tee.grid, tee.scene.cloud, tee.scene.surfaces, tee.inside);
  EXPECT_EQ(done.bores, 2u);
  EXPECT_EQ(done.extended, 1u);
  for (std::size_t v = 0; v < tee.grid.voxelCount(); ++v) {
    const Vec3 c = tee.grid.center(v);
    // The branch between the run's bore and where it was seen.
    if (c.head<2>().norm() < 4.5 && c.z() > 9.0 && c.z() < 21.0) {
      EXPECT_FALSE(tee.inside.test(v)) << c.transpose();
    }
    // The run's wall beside the branch stays.
    if (c.head<2>().norm() > 5.5 && c.tail<2>().norm() > 8.5 && Tee::solid(c)) {
      EXPECT_TRUE(tee.inside.test(v)) << c.transpose();
    }
  }
}

TEST(SeenBores, AFloorSeenInTheBranchStopsIt) {
  Tee tee;
  // A floor across the branch at z = 15, sampled as densely as its wall.
  tee.scene.disc(Vec3(0, 0, 15), Vec3::UnitZ(), 5.0, 150);
  const BoreOpening done = openSeenBores(tee.grid, tee.scene.cloud, tee.scene.surfaces, tee.inside);
  EXPECT_EQ(done.extended, 0u);
  for (std::size_t v = 0; v < tee.grid.voxelCount(); ++v) {
    const Vec3 c = tee.grid.center(v);
    if (c.head<2>().norm() < 4.5 && c.z() > 12.5 && c.z() < 14.5) {
      EXPECT_TRUE(tee.inside.test(v)) << c.transpose();
    }
  }
}

TEST(SeenBores, OnlyConcaveCylindersSeenAllAroundCount) {
  const VoxelGrid grid = testGrid();
  VoxelSet inside = labelsWhere(grid, [](const Vec3& p) { return std::abs(p.z()) < 30.0; });
  Scene scene;
  // Half a concave cylinder (a slot's end) and a convex one (a boss).
  scene.wall(Vec3::Zero(), Vec3::UnitZ(), 8.0, -10.0, 10.0, 800, true, std::numbers::pi);
  scene.wall(Vec3(10, 10, 0), Vec3::UnitZ(), 5.0, -10.0, 10.0, 800, true);
  scene.surfaces.back().convex = true;
  const VoxelSet before = inside;
  BoreOpeningOptions off;
  off.enabled = false;
  EXPECT_EQ(openSeenBores(grid, scene.cloud, scene.surfaces, inside, off).voxels, 0u);
  const BoreOpening done = openSeenBores(grid, scene.cloud, scene.surfaces, inside);
  EXPECT_EQ(done.bores, 0u);
  EXPECT_EQ(inside, before);
}

}  // namespace
}  // namespace csgvox
