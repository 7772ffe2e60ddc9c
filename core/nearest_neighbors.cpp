#include "core/nearest_neighbors.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <numeric>
#include <vector>

#include "core/statistics.h"

namespace csgvox {
namespace {

// Bits of each coordinate in a Morton key (3 x 21 = 63 bits).
constexpr int kMortonBits = 21;

// The low 21 bits of x spread to every third bit.
std::uint64_t spreadBits(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

std::vector<std::uint32_t> spatialOrder(std::span<const Vec3> points) {
  const std::size_t n = points.size();
  Aabb box;
  for (const Vec3& p : points) {
    if (p.allFinite()) box.extend(p);
  }
  const double top = double((std::uint64_t{1} << kMortonBits) - 1);
  Vec3 scale = Vec3::Zero();
  if (!box.isEmpty()) {
    for (int a = 0; a < 3; ++a) {
      const double extent = box.max[a] - box.min[a];
      scale[a] = extent > 0.0 ? top / extent : 0.0;
    }
  }
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          std::uint64_t key = 0;
          if (points[i].allFinite() && !box.isEmpty()) {
            for (int a = 0; a < 3; ++a) {
              const double c = std::clamp((points[i][a] - box.min[a]) * scale[a], 0.0, top);
              key |= spreadBits(std::uint64_t(c)) << a;
            }
          }
          keyed[i] = {key, std::uint32_t(i)};
        }
      });
  // The keys are distinct (each holds its index): one order, however the
  // sort splits its work.
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(n);
  for (std::size_t j = 0; j < n; ++j) order[j] = keyed[j].second;
  return order;
}

struct NearestNeighbors::Impl {
  struct Adaptor {
    std::vector<Vec3> points;  // in `order`
    std::size_t kdtree_get_point_count() const { return points.size(); }
    double kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][int(dim)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>,
                                                   Adaptor, 3, std::uint32_t>;
  Adaptor data;
  std::vector<std::uint32_t> order;  // position in `data` -> index as passed
  std::unique_ptr<Tree> tree;
};

NearestNeighbors::NearestNeighbors(std::span<const Vec3> points) : impl_(std::make_unique<Impl>()) {
  impl_->order = spatialOrder(points);
  impl_->data.points.resize(points.size());
  for (std::size_t j = 0; j < points.size(); ++j) impl_->data.points[j] = points[impl_->order[j]];
  impl_->tree =
      std::make_unique<Impl::Tree>(3, impl_->data, nanoflann::KDTreeSingleIndexAdaptorParams(16));
}

NearestNeighbors::~NearestNeighbors() = default;
NearestNeighbors::NearestNeighbors(NearestNeighbors&&) noexcept = default;
NearestNeighbors& NearestNeighbors::operator=(NearestNeighbors&&) noexcept = default;

std::size_t NearestNeighbors::size() const { return impl_->data.points.size(); }

std::span<const std::uint32_t> NearestNeighbors::order() const { return impl_->order; }

std::uint32_t NearestNeighbors::nearest(const Vec3& q, double* squaredDistance) const {
  std::uint32_t index = 0;
  double d2 = 0.0;
  nanoflann::KNNResultSet<double, std::uint32_t> result(1);
  result.init(&index, &d2);
  impl_->tree->findNeighbors(result, q.data(), nanoflann::SearchParams());
  if (squaredDistance) *squaredDistance = d2;
  return impl_->order[index];
}

void NearestNeighbors::kNearest(const Vec3& q, std::size_t k, std::vector<std::uint32_t>& indices,
                                std::vector<double>* squaredDistances) const {
  kNearestWithin(q, k, std::numeric_limits<double>::infinity(), indices, squaredDistances);
}

void NearestNeighbors::kNearestWithin(const Vec3& q, std::size_t k, double bound2,
                                      std::vector<std::uint32_t>& indices,
                                      std::vector<double>* squaredDistances) const {
  k = std::min(k, size());
  indices.resize(k);
  std::vector<double> local;
  std::vector<double>& d2 = squaredDistances ? *squaredDistances : local;
  d2.resize(k);
  if (k == 0) return;
  nanoflann::KNNResultSet<double, std::uint32_t> result(k);
  result.init(indices.data(), d2.data());
  // A bound replaces the result set's starting worst distance (the largest
  // double): the search skips what lies beyond it and, for what lies
  // within, takes the same steps as without it.
  const bool bounded = bound2 < std::numeric_limits<double>::max();
  if (bounded) d2[k - 1] = bound2;
  impl_->tree->findNeighbors(result, q.data(), nanoflann::SearchParams());
  if (bounded && result.size() < k) {
    kNearest(q, k, indices, squaredDistances);  // fewer than k within the bound
    return;
  }
  const std::size_t found = result.size();
  indices.resize(found);
  d2.resize(found);
  for (std::uint32_t& i : indices) i = impl_->order[i];
  // Points at one distance (copies of a point) by index, whatever the
  // order the tree visited them in.
  for (std::size_t a = 0; a < found;) {
    std::size_t b = a + 1;
    while (b < found && d2[b] == d2[a]) ++b;
    if (b - a > 1)
      std::sort(indices.begin() + std::ptrdiff_t(a), indices.begin() + std::ptrdiff_t(b));
    a = b;
  }
}

double kNearestBound(std::span<const Vec3> points, const Vec3& q,
                     std::span<const std::uint32_t> near, std::size_t k) {
  if (k == 0 || near.size() < k) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (std::uint32_t i : near) worst = std::max(worst, (points[i] - q).squaredNorm());
  return worst * (1.0 + 1e-9) + std::numeric_limits<double>::min();
}

double medianNearestDistance(std::span<const Vec3> points, const NearestNeighbors& nn,
                             std::size_t samples) {
  const std::size_t step = std::max<std::size_t>(1, points.size() / std::max<std::size_t>(1, samples));
  std::vector<double> d;
  std::vector<std::uint32_t> near;
  std::vector<double> d2;
  for (std::size_t i = 0; i < points.size(); i += step) {
    nn.kNearest(points[i], 2, near, &d2);
    if (d2.size() == 2) d.push_back(std::sqrt(d2[1]));
  }
  return d.empty() ? 0.0 : median(std::move(d));
}

}  // namespace csgvox
