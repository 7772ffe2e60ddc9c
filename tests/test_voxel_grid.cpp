// VoxelGrid: which region of space voxel (i, j, k) is, the grid laid around
// a box, the index <-> centre round trip and the voxel range of a box.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "voxel/voxel_grid.h"

namespace csgvox {
namespace {

Mat3 rotation(double degrees, const Vec3& axis) {
  return Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, axis.normalized())
      .toRotationMatrix();
}

TEST(VoxelGrid, AroundABoxPutsTheResolutionOnTheLongestSideWithItsMargin) {
  OrientedBox box;
  box.center = Vec3(1, 2, 3);
  box.axes = rotation(30, Vec3(1, 1, 0));
  box.halfSize = Vec3(30, 10, 5);  // 60 x 20 x 10
  const VoxelGrid grid = VoxelGrid::around(box, GridOptions{64, 2});
  // 60 units over 64 - 2 * 2 voxels.
  EXPECT_DOUBLE_EQ(grid.voxelSize(), 1.0);
  EXPECT_EQ(grid.dims(), (std::array<int, 3>{64, 24, 14}));
  // The grid is centred on the box, in the box's frame.
  const OrientedBox g = grid.box();
  EXPECT_LT((g.center - box.center).norm(), 1e-12);
  EXPECT_LT((g.axes - box.axes).norm(), 1e-15);
  EXPECT_LT((g.halfSize - Vec3(32, 12, 7)).norm(), 1e-12);
}

// A side a whole number of voxels long, give or take the rounding of fitted
// surfaces, gets no extra voxel: the grid, centred on the box, would
// otherwise shift by half a voxel and put a layer of voxel centres on each
// face of the part that lies a whole number of voxels from its ends (a
// centre on a face is labelled inside or outside at random).
TEST(VoxelGrid, ASideOfWholeVoxelsPlusRoundingGetsNoExtraVoxel) {
  OrientedBox box;
  box.center = Vec3(0, 0, 0);
  box.axes = Mat3::Identity();
  // 60 x 60 x 33 voxels of size 1/6 (10 x 10 x 5.5), the last side 3e-4
  // voxels longer: a frame tilted by 5e-6 rad around points 10 wide.
  box.halfSize = Vec3(5, 5, 2.75 + 0.5 * 5e-5);
  const VoxelGrid grid = VoxelGrid::around(box, GridOptions{64, 2});
  EXPECT_NEAR(grid.voxelSize(), 1.0 / 6.0, 1e-12);
  EXPECT_EQ(grid.dims(), (std::array<int, 3>{64, 64, 37}));
  // The top and bottom faces (z = +-2.75) and a face 3 voxels below the top
  // lie half a voxel from the nearest centres.
  for (const double z : {-2.75, 2.75, 2.25}) {
    const double k = grid.toGrid(Vec3(0, 0, z)).z() - 0.5;  // in centre units
    EXPECT_NEAR(std::abs(k - std::round(k)), 0.5, 1e-3) << z;
  }
  // A side a hundredth of a voxel longer than whole voxels still gets the
  // voxel that holds it.
  box.halfSize.z() = 2.75 + 0.5 * 0.02 / 6.0;
  EXPECT_EQ(VoxelGrid::around(box, GridOptions{64, 2}).dims()[2], 38);
}

TEST(VoxelGrid, VoxelCentresAndIndicesRoundTrip) {
  const VoxelGrid grid(Vec3(-1, 0, 2), rotation(40, Vec3(0, 1, 1)), 0.5, {5, 4, 3});
  ASSERT_EQ(grid.voxelCount(), 60u);
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 5; ++i) {
        const std::size_t idx = grid.index(i, j, k);
        EXPECT_EQ(idx, std::size_t((k * 4 + j) * 5 + i));  // i fastest
        EXPECT_LT((grid.center(idx) - grid.center(i, j, k)).norm(), 1e-12);
        // The centre is at grid coordinates (i, j, k) + 0.5.
        EXPECT_LT((grid.toGrid(grid.center(i, j, k)) - Vec3(i + 0.5, j + 0.5, k + 0.5)).norm(),
                  1e-12);
      }
    }
  }
  // Voxel (0, 0, 0) spans origin + axes * [0, size]^3.
  EXPECT_LT((grid.center(0, 0, 0) - (grid.origin() + grid.axes() * Vec3(0.25, 0.25, 0.25))).norm(),
            1e-12);
}

TEST(VoxelGrid, VoxelOfFindsTheVoxelHoldingAPointAndNothingOutside) {
  const VoxelGrid grid(Vec3(-1, 0, 2), rotation(40, Vec3(0, 1, 1)), 0.5, {5, 4, 3});
  const auto at = [&](double x, double y, double z) {
    return Vec3(grid.origin() + grid.axes() * (Vec3(x, y, z) * grid.voxelSize()));
  };
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 5; ++i) {
        EXPECT_EQ(grid.voxelOf(grid.center(i, j, k)), grid.index(i, j, k));
        // Near its lower corner and near its upper one, still inside.
        EXPECT_EQ(grid.voxelOf(at(i + 0.01, j + 0.01, k + 0.01)), grid.index(i, j, k));
        EXPECT_EQ(grid.voxelOf(at(i + 0.99, j + 0.99, k + 0.99)), grid.index(i, j, k));
      }
    }
  }
  // Just outside each face, far away, and not a number: no voxel.
  EXPECT_EQ(grid.voxelOf(at(-0.01, 1.5, 1.5)), VoxelGrid::npos);
  EXPECT_EQ(grid.voxelOf(at(5.01, 1.5, 1.5)), VoxelGrid::npos);
  EXPECT_EQ(grid.voxelOf(at(2.5, -0.01, 1.5)), VoxelGrid::npos);
  EXPECT_EQ(grid.voxelOf(at(2.5, 4.01, 1.5)), VoxelGrid::npos);
  EXPECT_EQ(grid.voxelOf(at(2.5, 1.5, -0.01)), VoxelGrid::npos);
  EXPECT_EQ(grid.voxelOf(at(2.5, 1.5, 3.01)), VoxelGrid::npos);
  EXPECT_EQ(grid.voxelOf(Vec3(1e300, -1e300, 1e300)), VoxelGrid::npos);
  EXPECT_EQ(grid.voxelOf(Vec3(std::nan(""), 0.0, 2.0)), VoxelGrid::npos);
}

TEST(VoxelGrid, VoxelRangeHoldsEveryCentreInTheBox) {
  const VoxelGrid grid(Vec3::Zero(), Mat3::Identity(), 1.0, {10, 10, 10});
  Aabb b;
  b.extend(Vec3(2.4, 2.6, -5));
  b.extend(Vec3(4.5, 2.7, 3.5));
  std::array<int, 3> lo{}, hi{};
  grid.voxelRange(b, lo, hi);
  // Conservative: every voxel whose centre is in the box is in the range.
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      for (int k = 0; k < 10; ++k) {
        if (b.contains(grid.center(i, j, k))) {
          EXPECT_TRUE(i >= lo[0] && i < hi[0] && j >= lo[1] && j < hi[1] && k >= lo[2] && k < hi[2])
              << i << " " << j << " " << k;
        }
      }
    }
  }
  // And clamped to the grid: the box reaches below z = 0.
  EXPECT_EQ(lo[2], 0);
  // A box outside the grid gives an empty range.
  Aabb away;
  away.extend(Vec3(20, 20, 20));
  away.extend(Vec3(21, 21, 21));
  grid.voxelRange(away, lo, hi);
  EXPECT_TRUE(lo[0] >= hi[0] || lo[1] >= hi[1] || lo[2] >= hi[2]);
  // An unbounded box covers the whole grid.
  grid.voxelRange(Aabb::everything(), lo, hi);
  EXPECT_EQ(lo, (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(hi, (std::array<int, 3>{10, 10, 10}));
}

TEST(VoxelGrid, RejectsDegenerateBoxesAndResolutions) {
  OrientedBox box;
  box.halfSize = Vec3(1, 1, 1);
  EXPECT_THROW(VoxelGrid::around(box, GridOptions{1, 0}), std::invalid_argument);
  box.halfSize = Vec3::Zero();
  EXPECT_THROW(VoxelGrid::around(box, {}), std::invalid_argument);
  box.halfSize = Vec3(std::numeric_limits<double>::infinity(), 1, 1);
  EXPECT_THROW(VoxelGrid::around(box, {}), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
