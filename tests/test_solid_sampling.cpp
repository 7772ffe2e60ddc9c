// Volume and overlap of solids by stratified sampling (core/solid_sampling.h).

#include <gtest/gtest.h>

#include <numbers>

#include "core/solid_sampling.h"

namespace csgvox {
namespace {

const Aabb kBox{Vec3(-2, -2, -2), Vec3(2, 2, 2)};

TEST(SolidSampling, PointsAreOnePerCellAndSeeded) {
  const std::vector<Vec3> p = stratifiedPoints(kBox, {4, 3, 2}, 5);
  ASSERT_EQ(p.size(), 24u);
  // x fastest, then y, then z: point (i, j, k) lies in its own cell.
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 4; ++i) {
        const Vec3 q = p[std::size_t((k * 3 + j) * 4 + i)] - kBox.min;
        EXPECT_EQ(int(q.x() / 1.0), i);
        EXPECT_EQ(int(q.y() / (4.0 / 3.0)), j);
        EXPECT_EQ(int(q.z() / 2.0), k);
      }
    }
  }
  EXPECT_EQ(stratifiedPoints(kBox, {4, 3, 2}, 5), p);
  EXPECT_NE(stratifiedPoints(kBox, {4, 3, 2}, 6), p);
  EXPECT_THROW(stratifiedPoints(Aabb{}, 3, 1), std::invalid_argument);
}

TEST(SolidSampling, VolumesOfABoxAndASphere) {
  const CsgTree box = CsgTree::leaf(Box{Vec3(0.1, 0, 0), Mat3::Identity(), Vec3(1, 0.5, 0.25)});
  EXPECT_NEAR(sampledVolume(box, kBox, 100), 1.0, 0.005);
  const CsgTree sphere = CsgTree::leaf(Sphere{Vec3::Zero(), 1.5});
  EXPECT_NEAR(sampledVolume(sphere, kBox, 100), 4.0 / 3.0 * std::numbers::pi * 3.375, 0.01);
  EXPECT_THROW(sampledVolume(box, kBox, 0), std::invalid_argument);
}

TEST(SolidSampling, IouOfShiftedBoxesIsExactUpToTheCellsOnFaces) {
  // Unit cubes shifted by 0.25 along x: IoU = 0.75 / 1.25 = 0.6. Faces at
  // round coordinates would decide whole layers of cell centres.
  const CsgTree a = CsgTree::leaf(Box{Vec3(0.5, 0.5, 0.5), Mat3::Identity(), Vec3::Constant(0.5)});
  const CsgTree b = CsgTree::leaf(Box{Vec3(0.75, 0.5, 0.5), Mat3::Identity(), Vec3::Constant(0.5)});
  EXPECT_NEAR(volumetricIou(a, b, 125), 0.6, 0.002);
  EXPECT_EQ(volumetricIou(a, a, 50), 1.0);
  EXPECT_THROW(volumetricIou(a, CsgTree{}), std::invalid_argument);
  EXPECT_THROW(volumetricIou(a, CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 0.0})),
               std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
