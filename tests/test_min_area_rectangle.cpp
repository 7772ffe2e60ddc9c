// Tests for primitives/min_area_rectangle.h: the minimum-area rectangle of
// 2D points against the rectangles they were drawn in and a brute-force
// search over every direction a point pair defines.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "primitives/min_area_rectangle.h"

namespace csgvox {
namespace {

using V2 = Eigen::Vector2d;

// Extents of the points along u and its perpendicular.
std::pair<double, double> extents(const std::vector<V2>& points, const V2& u) {
  const V2 n(-u.y(), u.x());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, lo2 = lo, hi2 = -lo;
  for (const V2& p : points) {
    lo = std::min(lo, p.dot(u)), hi = std::max(hi, p.dot(u));
    lo2 = std::min(lo2, p.dot(n)), hi2 = std::max(hi2, p.dot(n));
  }
  return {hi - lo, hi2 - lo2};
}

// Smallest bounding-rectangle area over the directions of all point pairs
// (a minimum rectangle has a side along a hull edge, hence along some pair).
double bruteForceArea(const std::vector<V2>& points) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (std::size_t j = i + 1; j < points.size(); ++j) {
      const V2 d = points[j] - points[i];
      if (d.norm() == 0.0) continue;
      const auto [a, b] = extents(points, d.normalized());
      best = std::min(best, a * b);
    }
  }
  return best;
}

// Points in the rectangle of the given centre, angle and size: its corners
// and `inside` random points.
std::vector<V2> rectanglePoints(const V2& centre, double angle, double length, double width,
                                int inside, std::mt19937_64& rng) {
  const V2 u(std::cos(angle), std::sin(angle)), n(-u.y(), u.x());
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  std::vector<V2> points;
  for (double s : {-0.5, 0.5}) {
    for (double t : {-0.5, 0.5}) points.push_back(centre + s * length * u + t * width * n);
  }
  for (int i = 0; i < inside; ++i) {
    points.push_back(centre + unit(rng) * length * u + unit(rng) * width * n);
  }
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

TEST(MinAreaRectangle, FindsTheRectangleThePointsFill) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(0.0, std::numbers::pi);
  for (int trial = 0; trial < 50; ++trial) {
    const double a = angle(rng);
    const std::vector<V2> points = rectanglePoints(V2(3.0, -2.0), a, 5.0, 2.0, 200, rng);
    const Rectangle2 r = minAreaRectangle(points);
    EXPECT_NEAR(r.length, 5.0, 1e-9) << "angle " << a;
    EXPECT_NEAR(r.width, 2.0, 1e-9) << "angle " << a;
    EXPECT_NEAR(r.direction.norm(), 1.0, 1e-12);
    EXPECT_GT(std::abs(r.direction.dot(V2(std::cos(a), std::sin(a)))), 1.0 - 1e-12);
  }
}

TEST(MinAreaRectangle, MatchesABruteForceSearchOnRandomPoints) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<V2> points;
    const int n = 3 + trial * 2;
    for (int i = 0; i < n; ++i) points.emplace_back(3.0 * gauss(rng), gauss(rng));
    const Rectangle2 r = minAreaRectangle(points);
    const double best = bruteForceArea(points);
    EXPECT_NEAR(r.length * r.width, best, 1e-9 * best) << n << " points";
    EXPECT_GE(r.length, r.width);
    // The rectangle bounds the points.
    const auto [along, across] = extents(points, r.direction);
    EXPECT_NEAR(along, r.length, 1e-9 * r.length);
    EXPECT_NEAR(across, r.width, 1e-9 * r.length);
  }
}

TEST(MinAreaRectangle, DegenerateInput) {
  EXPECT_EQ(minAreaRectangle({}).length, 0.0);
  const Rectangle2 point = minAreaRectangle({V2(1, 2), V2(1, 2), V2(1, 2)});
  EXPECT_EQ(point.length, 0.0);
  EXPECT_EQ(point.width, 0.0);
  // Collinear points (with copies): their segment.
  const Rectangle2 line =
      minAreaRectangle({V2(0, 0), V2(3, 4), V2(1.5, 2), V2(3, 4), V2(0.3, 0.4)});
  EXPECT_NEAR(line.length, 5.0, 1e-12);
  EXPECT_EQ(line.width, 0.0);
  EXPECT_GT(std::abs(line.direction.dot(V2(0.6, 0.8))), 1.0 - 1e-12);
  // A triangle: the rectangle has a side along one of its edges.
  const std::vector<V2> triangle{V2(0, 0), V2(4, 0), V2(1, 3)};
  const Rectangle2 t = minAreaRectangle(triangle);
  EXPECT_NEAR(t.length * t.width, bruteForceArea(triangle), 1e-12);
}

}  // namespace
}  // namespace csgvox
