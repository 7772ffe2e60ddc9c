#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "core/nearest_neighbors.h"

namespace csgvox {
namespace {

std::vector<Vec3> randomPoints(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::vector<Vec3> p(n);
  for (Vec3& q : p) q = Vec3(u(rng), u(rng), 0.2 * u(rng));
  return p;
}

// The k nearest by brute force: by distance, then by index.
std::vector<std::uint32_t> bruteForce(const std::vector<Vec3>& p, const Vec3& q, std::size_t k) {
  std::vector<std::uint32_t> idx(p.size());
  std::iota(idx.begin(), idx.end(), 0u);
  std::stable_sort(idx.begin(), idx.end(), [&](std::uint32_t a, std::uint32_t b) {
    return (p[a] - q).squaredNorm() < (p[b] - q).squaredNorm();
  });
  idx.resize(std::min(k, p.size()));
  return idx;
}

TEST(NearestNeighbors, KNearestEqualsBruteForceWithIndicesAsPassed) {
  const std::vector<Vec3> p = randomPoints(3000, 7);
  const NearestNeighbors nn(p);
  std::vector<std::uint32_t> found;
  std::vector<double> d2;
  for (const Vec3& q : randomPoints(200, 8)) {
    nn.kNearest(q, 12, found, &d2);
    EXPECT_EQ(found, bruteForce(p, q, 12));
    ASSERT_EQ(d2.size(), 12u);
    for (std::size_t j = 0; j < found.size(); ++j) {
      EXPECT_DOUBLE_EQ(d2[j], (p[found[j]] - q).squaredNorm());
    }
    double nd2 = -1.0;
    EXPECT_EQ(nn.nearest(q, &nd2), bruteForce(p, q, 1).front());
    EXPECT_DOUBLE_EQ(nd2, d2.front());
  }
}

TEST(NearestNeighbors, CopiesOfAPointComeByIndex) {
  std::vector<Vec3> p = randomPoints(500, 3);
  // Five copies of one point, spread over the index range.
  for (std::uint32_t i : {40u, 410u, 7u, 250u}) p[i] = p[123];
  const NearestNeighbors nn(p);
  std::vector<std::uint32_t> found;
  nn.kNearest(p[123], 5, found);
  EXPECT_EQ(found, (std::vector<std::uint32_t>{7, 40, 123, 250, 410}));
}

// A loop over every point in order(), each query bounded by the previous
// one's neighbours, gives kNearest's indices and distances exactly, copies
// of points included; so does a bound that holds fewer than k points.
TEST(NearestNeighbors, BoundedQueriesGiveTheSameNeighbours) {
  std::vector<Vec3> p = randomPoints(3000, 11);
  for (std::size_t i = 0; i < 300; ++i) p.push_back(p[7 * i]);  // copies
  const NearestNeighbors nn(p);
  for (const std::size_t k : {1u, 4u, 13u}) {
    std::vector<std::uint32_t> previous, bounded, plain;
    std::vector<double> boundedD2, plainD2;
    std::size_t tight = 0;
    for (std::size_t at = 0; at < p.size(); ++at) {
      const Vec3& q = p[nn.order()[at]];
      const double bound = kNearestBound(p, q, previous, k);
      nn.kNearestWithin(q, k, bound, bounded, &boundedD2);
      nn.kNearest(q, k, plain, &plainD2);
      ASSERT_EQ(bounded, plain) << "k " << k << " at " << at;
      ASSERT_EQ(boundedD2, plainD2) << "k " << k << " at " << at;
      // The bound holds the k-th neighbour: it is a bound.
      if (at > 0) {
        ASSERT_GE(bound, plainD2.back());
        tight += bound < 10.0 * plainD2.back() + 1e-9;
      }
      previous = bounded;
    }
    // Neighbours of the previous point in order() are near: the bounds are
    // mostly tight (not infinite), so the searches are really bounded. (With
    // k = 1 each point is its own nearest, at distance 0.)
    if (k > 1) {
      EXPECT_GT(tight, p.size() / 2) << "k " << k;
    }
  }
  // Bounds that hold fewer than k points (none, or one) fall back.
  std::vector<std::uint32_t> got, want;
  std::vector<double> gotD2, wantD2;
  for (const double bound : {0.0, 1e-6, -1.0}) {
    nn.kNearestWithin(p[5], 13, bound, got, &gotD2);
    nn.kNearest(p[5], 13, want, &wantD2);
    EXPECT_EQ(got, want);
    EXPECT_EQ(gotD2, wantD2);
  }
  EXPECT_EQ(kNearestBound(p, p[0], std::vector<std::uint32_t>{1, 2}, 3),
            std::numeric_limits<double>::infinity());
  EXPECT_GE(kNearestBound(p, p[0], std::vector<std::uint32_t>{1, 2}, 2),
            (p[1] - p[0]).squaredNorm());
}

TEST(NearestNeighbors, OrderIsAPermutationThatKeepsNeighboursTogether) {
  const std::vector<Vec3> p = randomPoints(20000, 11);
  const NearestNeighbors nn(p);
  const std::span<const std::uint32_t> order = nn.order();
  std::vector<std::uint32_t> sorted(order.begin(), order.end());
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::uint32_t> all(p.size());
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(sorted, all);
  EXPECT_EQ(std::vector<std::uint32_t>(order.begin(), order.end()), spatialOrder(p));
  // Consecutive points of the order lie far closer together than
  // consecutive points of the random input.
  double inOrder = 0.0, asPassed = 0.0;
  for (std::size_t j = 1; j < p.size(); ++j) {
    inOrder += (p[order[j]] - p[order[j - 1]]).norm();
    asPassed += (p[j] - p[j - 1]).norm();
  }
  EXPECT_LT(inOrder, 0.1 * asPassed);
}

// The order is the same however many threads compute and sort the keys.
TEST(NearestNeighbors, SpatialOrderIsTheSameOnAnyNumberOfThreads) {
  std::vector<Vec3> p = randomPoints(30000, 12);
  p.insert(p.end(), p.begin(), p.begin() + 500);  // copies: ties go by index
  std::vector<std::uint32_t> one;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = spatialOrder(p);
  }
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
  EXPECT_EQ(spatialOrder(p), one);
}

TEST(NearestNeighbors, SpatialOrderHandlesFlatAndDegenerateSets) {
  EXPECT_TRUE(spatialOrder({}).empty());
  const std::vector<Vec3> same(4, Vec3(1.0, 2.0, 3.0));
  EXPECT_EQ(spatialOrder(same), (std::vector<std::uint32_t>{0, 1, 2, 3}));
  // A line along x: the order is by x.
  const std::vector<Vec3> line = {Vec3(3, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(0, 0, 0)};
  EXPECT_EQ(spatialOrder(line), (std::vector<std::uint32_t>{3, 1, 2, 0}));
}

TEST(NearestNeighbors, MedianNearestDistanceOfTwoSpacings) {
  // Points 0.5 apart along a row, then rows 2 apart: every point's nearest
  // other one lies 0.5 away, except the lone point of the last row (2).
  std::vector<Vec3> p;
  for (int row = 0; row < 3; ++row) {
    for (int k = 0; k < 10; ++k) p.emplace_back(0.5 * k, 2.0 * row, 0.0);
  }
  p.emplace_back(0.0, 6.0, 0.0);
  const NearestNeighbors nn(p);
  EXPECT_DOUBLE_EQ(medianNearestDistance(p, nn), 0.5);
  // Every 10th point (indices 0, 10, 20, 30: three at 0.5, the lone one at 2).
  EXPECT_DOUBLE_EQ(medianNearestDistance(p, nn, 3), 0.5);
  // Two pairs, 1 and 3 apart: the upper of the two middle values.
  const std::vector<Vec3> pairs = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(10, 0, 0), Vec3(13, 0, 0)};
  EXPECT_DOUBLE_EQ(medianNearestDistance(pairs, NearestNeighbors(pairs)), 3.0);
  const std::vector<Vec3> lone = {Vec3::Zero()};
  EXPECT_EQ(medianNearestDistance(lone, NearestNeighbors(lone)), 0.0);
  const std::vector<Vec3> pair = {Vec3::Zero(), Vec3(0, 0, 3)};
  EXPECT_DOUBLE_EQ(medianNearestDistance(pair, NearestNeighbors(pair)), 3.0);
}

}  // namespace
}  // namespace csgvox
