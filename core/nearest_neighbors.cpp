#include "core/nearest_neighbors.h"

#include <nanoflann.hpp>

namespace csgvox {

struct NearestNeighbors::Impl {
  struct Adaptor {
    std::vector<Vec3> points;
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
  std::unique_ptr<Tree> tree;
};

NearestNeighbors::NearestNeighbors(std::span<const Vec3> points) : impl_(std::make_unique<Impl>()) {
  impl_->data.points.assign(points.begin(), points.end());
  impl_->tree =
      std::make_unique<Impl::Tree>(3, impl_->data, nanoflann::KDTreeSingleIndexAdaptorParams(16));
}

NearestNeighbors::~NearestNeighbors() = default;
NearestNeighbors::NearestNeighbors(NearestNeighbors&&) noexcept = default;
NearestNeighbors& NearestNeighbors::operator=(NearestNeighbors&&) noexcept = default;

std::size_t NearestNeighbors::size() const { return impl_->data.points.size(); }

std::uint32_t NearestNeighbors::nearest(const Vec3& q, double* squaredDistance) const {
  std::uint32_t index = 0;
  double d2 = 0.0;
  nanoflann::KNNResultSet<double, std::uint32_t> result(1);
  result.init(&index, &d2);
  impl_->tree->findNeighbors(result, q.data(), nanoflann::SearchParams());
  if (squaredDistance) *squaredDistance = d2;
  return index;
}

void NearestNeighbors::kNearest(const Vec3& q, std::size_t k, std::vector<std::uint32_t>& indices,
                                std::vector<double>* squaredDistances) const {
  k = std::min(k, size());
  indices.resize(k);
  std::vector<double> local;
  std::vector<double>& d2 = squaredDistances ? *squaredDistances : local;
  d2.resize(k);
  if (k == 0) return;
  nanoflann::KNNResultSet<double, std::uint32_t> result(k);
  result.init(indices.data(), d2.data());
  impl_->tree->findNeighbors(result, q.data(), nanoflann::SearchParams());
  indices.resize(result.size());
  d2.resize(result.size());
}

}  // namespace csgvox
