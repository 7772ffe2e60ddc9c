// Tests for primitives/bounding_box.h: the minimal oriented box of points
// sampled in a rotated box, determinism per seed, and flat or tiny sets.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "primitives/bounding_box.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::Rng;

// Points filling a box of the given half sizes (longest first), rotated and moved.
std::vector<Vec3> boxPoints(const Mat3& rotation, const Vec3& centre, const Vec3& half, int n,
                            Rng& rng) {
  std::vector<Vec3> points;
  for (int i = 0; i < n; ++i) {
    Vec3 local;
    for (int k = 0; k < 3; ++k) local[k] = test::uniform(rng, -half[k], half[k]);
    points.push_back(centre + rotation * local);
  }
  for (int corner = 0; corner < 8; ++corner) {  // the corners make the box exact
    const Vec3 sign(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1);
    points.push_back(centre + rotation * sign.cwiseProduct(half));
  }
  return points;
}

void expectOrthonormalRightHanded(const Mat3& axes) {
  EXPECT_TRUE((axes.transpose() * axes).isApprox(Mat3::Identity(), 1e-12));
  EXPECT_NEAR(axes.determinant(), 1.0, 1e-12);
}

TEST(MinimalOrientedBox, RecoversARotatedBox) {
  Rng rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    const Mat3 rotation = test::randomRotation(rng);
    const Vec3 centre(10.0, -4.0, 2.5), half(3.0, 2.0, 0.5);
    const std::vector<Vec3> points = boxPoints(rotation, centre, half, 2000, rng);
    const OrientedBox box = minimalOrientedBox(points, {});
    expectOrthonormalRightHanded(box.axes);
    test::expectNear(box.halfSize, half, 1e-3 * half[0]);
    test::expectNear(box.center, centre, 1e-3 * half[0]);
    for (int k = 0; k < 3; ++k) EXPECT_GT(std::abs(box.axes.col(k).dot(rotation.col(k))), 0.9999);
  }
}

TEST(MinimalBoxFrame, SameSeedSameFrameAndSearchOnASubset) {
  Rng rng(5);
  const std::vector<Vec3> points =
      boxPoints(test::randomRotation(rng), Vec3(1, 2, 3), Vec3(4, 2, 1), 5000, rng);
  const MinimalBoxOptions options{7, 300};
  EXPECT_EQ(minimalBoxFrame(points, options), minimalBoxFrame(points, options));
  const Mat3 all = minimalBoxFrame(points, {7, 0});
  const Mat3 subset = minimalBoxFrame(points, options);
  expectOrthonormalRightHanded(all);
  expectOrthonormalRightHanded(subset);
  // A subset of a filled box still finds its orientation, roughly.
  for (int k = 0; k < 3; ++k) {
    double best = 0.0;
    for (int j = 0; j < 3; ++j) best = std::max(best, std::abs(all.col(k).dot(subset.col(j))));
    EXPECT_GT(best, 0.99);
  }
}

// Large sets are searched on the points that may be corners of their convex
// hull: what is dropped changes nothing. 60 000 points inside a box whose
// corners are the only hull corners give the frame of the 8 corners alone
// (searched without the filter), with the corners anywhere in the input.
TEST(MinimalBoxFrame, ALargeSetGivesTheFrameOfItsHullCorners) {
  Rng rng(9);
  for (int trial = 0; trial < 3; ++trial) {
    const Mat3 rotation = test::randomRotation(rng);
    const Vec3 centre(5, -3, 8), half(6, 2.5, 1);
    std::vector<Vec3> points = boxPoints(rotation, centre, half, 60000, rng);
    const std::vector<Vec3> corners(points.end() - 8, points.end());
    // Move the corners to scattered places in the input.
    for (int c = 0; c < 8; ++c) {
      std::swap(points[points.size() - 8 + std::size_t(c)],
                points[std::size_t(977 * c + 13 * trial + 5)]);
    }
    EXPECT_EQ(minimalBoxFrame(points, {3, 0}), minimalBoxFrame(corners, {3, 0})) << trial;
  }
}

// Points on a part's faces, as a scan gives them: many lie on the filter's
// hull faces up to rounding. The search finds the same frame with the
// filter and without it. This does not check the exact predicate itself:
// with its sign flipped the frames still agree, for the points it decides
// (within 1e-9 of the extent from a face's plane) change no frame here.
TEST(MinimalBoxFrame, TheHullFilterKeepsTheFrameOfPointsOnFaces) {
  Rng rng(21);
  for (int trial = 0; trial < 3; ++trial) {
    const Mat3 rotation = test::randomRotation(rng);
    const Vec3 centre(-2, 7, 1), half(5, 3, 1.5);
    std::vector<Vec3> points;
    for (int i = 0; i < 40000; ++i) {
      Vec3 local;
      for (int k = 0; k < 3; ++k) local[k] = test::uniform(rng, -half[k], half[k]);
      const int face = i % 6;  // onto one of the six faces
      local[face / 2] = face % 2 ? half[face / 2] : -half[face / 2];
      points.push_back(centre + rotation * local);
    }
    // A boss: a cylinder's side standing on the top face.
    for (int i = 0; i < 10000; ++i) {
      const double a = test::uniform(rng, 0.0, 2.0 * std::numbers::pi);
      const Vec3 local(1.5 * std::cos(a), 1.5 * std::sin(a),
                       half[2] + test::uniform(rng, 0.0, 2.0));
      points.push_back(centre + rotation * local);
    }
    MinimalBoxOptions all{4, 0};
    all.hullFilter = false;
    EXPECT_EQ(minimalBoxFrame(points, {4, 0}), minimalBoxFrame(points, all)) << trial;
  }
}

TEST(MinimalBoxFrame, FlatAndTinySetsTakeTheirPrincipalAxes) {
  // Points on the plane z = 1 (a rectangle 4 x 1): CGAL's search needs a
  // solid hull, so the frame is the principal one, the normal last.
  Rng rng(9);
  std::vector<Vec3> flat;
  for (int i = 0; i < 500; ++i) {
    flat.emplace_back(test::uniform(rng, -2, 2), test::uniform(rng, -0.5, 0.5), 1.0);
  }
  const Mat3 frame = minimalBoxFrame(flat);
  expectOrthonormalRightHanded(frame);
  EXPECT_GT(std::abs(frame.col(0).x()), 0.99);
  EXPECT_GT(std::abs(frame.col(2).z()), 1.0 - 1e-12);
  const OrientedBox box = minimalOrientedBox(flat);
  EXPECT_NEAR(box.halfSize[2], 0.0, 1e-12);

  const std::vector<Vec3> three{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 1, 0)};
  expectOrthonormalRightHanded(minimalBoxFrame(three));
  EXPECT_THROW(minimalOrientedBox(three), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
