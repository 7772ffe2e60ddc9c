#include <gtest/gtest.h>

#include "mesh/fit_metrics.h"
#include "mesh/surface_sampler.h"

namespace csgvox {
namespace {

CsgTree bracket(const Vec3& shift = Vec3::Zero()) {
  return CsgTree::subtract(
      {CsgTree::unite({CsgTree::leaf(Box{Vec3(0, 0, 5) + shift, Mat3::Identity(), Vec3(30, 20, 5)}),
                       CsgTree::leaf(Cylinder{Vec3(0, 0, 15) + shift, Vec3::UnitZ(), 10, 21})}),
       CsgTree::leaf(Cylinder{Vec3(0, 0, 15) + shift, Vec3::UnitZ(), 5, 40}),
       CsgTree::leaf(Sphere{Vec3(30, 20, 10) + shift, 8})});
}

TEST(FitMetrics, ExactScanHasZeroError) {
  const CsgTree tree = bracket();
  const SurfaceSample s = sampleSurface(tree, SampleOptions{10000, 0, 0, 0.05, 3});
  const FitMetrics m = evaluateFit(tree, s.cloud);
  const double d = m.diagonal;
  EXPECT_EQ(m.points, 10000u);
  EXPECT_LT(m.rmse, 1e-9 * d);
  EXPECT_LT(m.surfaceRmse, 5e-4 * d);  // limited by the boundary sampling density
  EXPECT_LT(m.chamfer, 2e-3 * d);
  EXPECT_DOUBLE_EQ(m.withinFraction, 1.0);
  EXPECT_GT(m.normalAgreement, 0.99);
  EXPECT_GT(m.normalsWithin10Deg, 0.99);
}

TEST(FitMetrics, NoisyScanErrorMatchesTheNoise) {
  const CsgTree tree = bracket();
  const double sigma = 0.005;
  const SurfaceSample s = sampleSurface(tree, SampleOptions{20000, sigma, 0, 0.05, 4});
  const FitMetrics m = evaluateFit(tree, s.cloud);
  // Isotropic noise: the distance to the surface is its normal component.
  const double expected = sigma * s.diagonal;
  EXPECT_NEAR(m.rmse / expected, 1.0, 0.1);
  EXPECT_NEAR(m.surfaceRmse / expected, 1.0, 0.1);
}

TEST(FitMetrics, ShiftedTreeShowsTheShift) {
  const SurfaceSample s = sampleSurface(bracket(), SampleOptions{10000, 0, 0, 0.05, 5});
  const double shift = 0.5;
  const FitMetrics m = evaluateFit(bracket(Vec3(0, 0, shift)), s.cloud);
  // Faces normal to z are off by the shift, the others are not: the RMS lies
  // strictly between 0 and the shift.
  EXPECT_GT(m.surfaceRmse, 0.3 * shift);
  EXPECT_LT(m.surfaceRmse, 1.0001 * shift);
  EXPECT_LE(m.maxDistance, 1.05 * shift);
  EXPECT_GT(m.maxDistance, 0.9 * shift);
}

TEST(FitMetrics, WrongTreeIsFarAndDisagreesOnNormals) {
  const SurfaceSample s = sampleSurface(bracket(), SampleOptions{5000, 0, 0, 0.05, 6});
  const CsgTree ball = CsgTree::leaf(Sphere{Vec3(0, 0, 10), 20});
  const FitMetrics m = evaluateFit(ball, s.cloud);
  EXPECT_GT(m.surfaceRmse, 0.05 * m.diagonal);
  EXPECT_LT(m.withinFraction, 0.5);
  EXPECT_LT(m.normalsWithin10Deg, 0.5);
}

TEST(FitMetrics, RejectsAnEmptyScan) {
  EXPECT_THROW(evaluateFit(bracket(), PointCloud{}), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
