#include "core/principal_axes.h"

#include <Eigen/Eigenvalues>

namespace csgvox {
namespace {

// Mean and covariance from a point accessor; then the eigen-decomposition.
template <class PointAt>
PrincipalAxes analyse(std::size_t n, PointAt at) {
  PrincipalAxes pa;
  if (n == 0) return pa;
  for (std::size_t i = 0; i < n; ++i) pa.mean += at(i);
  pa.mean /= double(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = at(i) - pa.mean;
    pa.covariance += d * d.transpose();
  }
  pa.covariance /= double(n);
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(pa.covariance);
  // Eigen sorts the eigenvalues in increasing order.
  for (int k = 0; k < 3; ++k) pa.axes.col(k) = eig.eigenvectors().col(2 - k);
  pa.variances = eig.eigenvalues().reverse();
  return pa;
}

}  // namespace

PrincipalAxes principalAxes(std::span<const Vec3> points) {
  return analyse(points.size(), [&](std::size_t i) -> const Vec3& { return points[i]; });
}

PrincipalAxes principalAxes(std::span<const Vec3> points, std::span<const std::uint32_t> indices) {
  return analyse(indices.size(), [&](std::size_t i) -> const Vec3& { return points[indices[i]]; });
}

}  // namespace csgvox
