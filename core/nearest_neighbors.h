#pragma once
/// Exact nearest-neighbour queries over a fixed set of 3D points (a k-d tree).

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// A k-d tree over points. The points are copied; queries are thread-safe.
class NearestNeighbors {
 public:
  explicit NearestNeighbors(std::span<const Vec3> points);
  ~NearestNeighbors();
  NearestNeighbors(NearestNeighbors&&) noexcept;
  NearestNeighbors& operator=(NearestNeighbors&&) noexcept;

  std::size_t size() const;
  /// Index of the point nearest to q and its squared distance. Requires size() > 0.
  std::uint32_t nearest(const Vec3& q, double* squaredDistance = nullptr) const;
  /// Indices of the min(k, size()) nearest points, closest first.
  void kNearest(const Vec3& q, std::size_t k, std::vector<std::uint32_t>& indices,
                std::vector<double>* squaredDistances = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace csgvox
