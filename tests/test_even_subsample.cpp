// The even subsample detection searches on (primitives/even_subsample.h).

#include "primitives/even_subsample.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace csgvox::test {
namespace {

// A 100 x 100 square in the plane z = 0: `dense` points on x < 50 and
// `sparse` on x >= 50, with Gaussian noise `sigma` along z.
std::vector<Vec3> twoDensities(std::size_t dense, std::size_t sparse, double sigma,
                               unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 50.0), y(0.0, 100.0);
  std::normal_distribution<double> z(0.0, sigma > 0.0 ? sigma : 1.0);
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < dense + sparse; ++i) {
    const double x = u(rng) + (i < dense ? 0.0 : 50.0);
    points.emplace_back(x, y(rng), sigma > 0.0 ? z(rng) : 0.0);
  }
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

TEST(EvenSubsample, KeepsEveryPointOfASmallCloud) {
  const std::vector<Vec3> points = twoDensities(300, 200, 0.0);
  SubsampleOptions o;
  o.points = 500;
  const std::vector<std::uint32_t> kept = evenSubsample(points, 0.0, o);
  ASSERT_EQ(kept.size(), points.size());
  for (std::size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(kept[i], i);
}

TEST(EvenSubsample, ThinsTheDenseRegionAndKeepsTheSparseOne) {
  const std::vector<Vec3> points = twoDensities(90000, 10000, 0.0);
  SubsampleOptions o;
  o.points = 30000;
  const std::vector<std::uint32_t> kept = evenSubsample(points, 0.0, o);
  EXPECT_NEAR(double(kept.size()), double(o.points), 0.03 * double(o.points));
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  EXPECT_TRUE(std::adjacent_find(kept.begin(), kept.end()) == kept.end());
  std::size_t sparseKept = 0;
  for (std::uint32_t i : kept) sparseKept += points[i].x() >= 50.0;
  // The sparse half keeps nearly all of its points, the dense one (nine
  // times as dense) is thinned to what is left.
  EXPECT_GE(double(sparseKept), 0.9 * 10000.0);
  EXPECT_LE(double(kept.size() - sparseKept), 0.25 * 90000.0);
}

TEST(EvenSubsample, KeepsTheNoiseOfANoisySurface) {
  const double sigma = 0.5;
  const std::vector<Vec3> points = twoDensities(100000, 100000, sigma);
  SubsampleOptions o;
  o.points = 20000;
  const std::vector<std::uint32_t> kept = evenSubsample(points, sigma, o);
  double sum = 0.0;
  for (std::uint32_t i : kept) sum += points[i].z() * points[i].z();
  EXPECT_NEAR(std::sqrt(sum / double(kept.size())), sigma, 0.05 * sigma);
}

TEST(EvenSubsample, SameSeedSameIndicesAtAnyThreadCount) {
  const std::vector<Vec3> points = twoDensities(60000, 20000, 0.1);
  SubsampleOptions o;
  o.points = 10000;
  o.seed = 7;
  std::vector<std::uint32_t> one, two;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = evenSubsample(points, 0.1, o);
  }
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = evenSubsample(points, 0.1, o);
  }
  EXPECT_EQ(one, two);
  o.seed = 8;
  EXPECT_NE(evenSubsample(points, 0.1, o), one);
}

TEST(EvenSubsample, RejectsOptionsOutOfRange) {
  const std::vector<Vec3> points = twoDensities(100, 100, 0.0);
  SubsampleOptions o;
  o.points = 0;
  EXPECT_THROW(evenSubsample(points, 0.0, o), std::invalid_argument);
  EXPECT_THROW(evenSubsample(points, -1.0, {}), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox::test
