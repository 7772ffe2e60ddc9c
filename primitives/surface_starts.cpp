// Closed-form starts of surfaces on their points and normals, to be polished
// by fitSurface: PCA plane, algebraic sphere, axes of surfaces of revolution
// from the normals, then line or circle fits in the (height, radius) plane.

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/principal_axes.h"
#include "primitives/surface_fit.h"
#include "primitives/surface_fit_internal.h"

namespace csgvox {

namespace surface_fit_detail {

bool fitCircle(const PointCloud& cloud, std::span<const std::uint32_t> indices, const Vec3& origin,
               const Vec3& u, const Vec3& v, Vec3& centre, double& radius) {
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (std::uint32_t i : indices) {
    const Vec3 d = cloud.points[i] - origin;
    const double x = d.dot(u), y = d.dot(v);
    const Eigen::Vector3d row(2.0 * x, 2.0 * y, 1.0);
    ata += row * row.transpose();
    atb += row * (x * x + y * y);
  }
  const Eigen::Vector3d sol = ata.ldlt().solve(atb);
  if (!sol.allFinite()) return false;
  const double r2 = sol[2] + sol[0] * sol[0] + sol[1] * sol[1];
  if (!(r2 > 0.0)) return false;
  centre = origin + sol[0] * u + sol[1] * v;
  radius = std::sqrt(r2);
  return true;
}

}  // namespace surface_fit_detail

namespace {

using namespace surface_fit_detail;

// Least-squares meeting point, in the plane through `origin` spanned by u and
// v, of the points' normal lines projected into that plane: the axis of a
// surface of revolution with axis u x v.
bool axisPointFromNormals(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                          const Vec3& origin, const Vec3& u, const Vec3& v, Vec3& point) {
  Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
  Eigen::Vector2d atb = Eigen::Vector2d::Zero();
  for (std::uint32_t i : indices) {
    const Vec3 d = cloud.points[i] - origin;
    const Eigen::Vector2d q(d.dot(u), d.dot(v));
    Eigen::Vector2d n(cloud.normals[i].dot(u), cloud.normals[i].dot(v));
    const double len = n.norm();
    if (!(len > 1e-6)) continue;
    n /= len;
    // Distance from x to the line through q along n: |P (x - q)|, P = I - n n^T.
    const Eigen::Matrix2d proj = Eigen::Matrix2d::Identity() - n * n.transpose();
    ata += proj;
    atb += proj * q;
  }
  if (std::abs(ata.determinant()) < 1e-12 * std::max(1.0, ata.trace() * ata.trace())) return false;
  const Eigen::Vector2d x = ata.ldlt().solve(atb);
  if (!x.allFinite()) return false;
  point = origin + x[0] * u + x[1] * v;
  return true;
}

// Heights along `axis` and distances from it of the points.
void heightRadius(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                  const Vec3& point, const Vec3& axis, std::vector<double>& z,
                  std::vector<double>& rho) {
  z.clear();
  rho.clear();
  for (std::uint32_t i : indices) {
    const Vec3 d = cloud.points[i] - point;
    z.push_back(d.dot(axis));
    rho.push_back((d - z.back() * axis).norm());
  }
}

bool initialCone(const PointCloud& cloud, std::span<const std::uint32_t> indices, const Vec3& mean,
                 Surface& s) {
  // The normals of a cone make a constant angle with its axis: they lie in a
  // plane perpendicular to it.
  Vec3 axis = principalAxes(cloud.normals, indices).leastAxis().normalized();
  const Mat3 f = frameFromAxis(axis);
  Vec3 point;
  if (!axisPointFromNormals(cloud, indices, mean, f.col(0), f.col(1), point)) return false;
  std::vector<double> z, rho;
  heightRadius(cloud, indices, point, axis, z, rho);
  // rho = alpha z + beta.
  Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
  Eigen::Vector2d atb = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < z.size(); ++k) {
    const Eigen::Vector2d row(z[k], 1.0);
    ata += row * row.transpose();
    atb += row * rho[k];
  }
  const Eigen::Vector2d sol = ata.ldlt().solve(atb);
  const double alpha = sol[0], beta = sol[1];
  if (!sol.allFinite() || std::abs(alpha) < 1e-6) return false;
  const Vec3 apex = point - (beta / alpha) * axis;
  if (alpha < 0.0) axis = -axis;  // the radius grows along the axis
  s.shape = ConeSurface{apex, axis, std::atan(std::abs(alpha))};
  return true;
}

bool initialTorus(const PointCloud& cloud, std::span<const std::uint32_t> indices, const Vec3& mean,
                  Surface& s) {
  // The axis meets every normal line: in Pluecker coordinates (a, m) of the
  // axis, a.(p x n) + n.m = 0 for every point p with normal n.
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::uint32_t i : indices) {
    const Vec3 p = cloud.points[i] - mean;
    const Vec3& n = cloud.normals[i];
    Eigen::Matrix<double, 6, 1> row;
    row << p.cross(n), n;
    m += row * row.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(m);
  const Eigen::Matrix<double, 6, 1> line = eig.eigenvectors().col(0);
  Vec3 axis = line.head<3>();
  const double len = axis.norm();
  if (!(len > 1e-9)) return false;
  const Vec3 moment = line.tail<3>() / len;
  axis /= len;
  const Vec3 point = mean + axis.cross(moment);  // m = c x a  =>  c = a x m for unit a
  std::vector<double> z, rho;
  heightRadius(cloud, indices, point, axis, z, rho);
  // Circle (z - zc)^2 + (rho - R)^2 = r^2 in the half-plane.
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < z.size(); ++k) {
    const Eigen::Vector3d row(2.0 * z[k], 2.0 * rho[k], 1.0);
    ata += row * row.transpose();
    atb += row * (z[k] * z[k] + rho[k] * rho[k]);
  }
  const Eigen::Vector3d sol = ata.ldlt().solve(atb);
  const double r2 = sol[2] + sol[0] * sol[0] + sol[1] * sol[1];
  if (!sol.allFinite() || !(r2 > 0.0)) return false;
  s.shape = TorusSurface{point + sol[0] * axis, axis, sol[1], std::sqrt(r2)};
  return true;
}

}  // namespace

bool initialSurface(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                    SurfaceType type, Surface& surface) {
  if (indices.size() < 6) return false;
  const PrincipalAxes spread = principalAxes(cloud.points, indices);
  const Vec3& mean = spread.mean;
  Surface s;
  s.inliers.assign(indices.begin(), indices.end());
  switch (type) {
    case SurfaceType::Plane: {
      const Vec3 n = spread.leastAxis().normalized();
      s.shape = PlaneSurface{n, n.dot(mean)};
      break;
    }
    case SurfaceType::Sphere: {
      // |p - m|^2 = 2 c'.(p - m) + k  (centred for conditioning).
      Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
      Eigen::Vector4d atb = Eigen::Vector4d::Zero();
      for (std::uint32_t i : indices) {
        const Vec3 d = cloud.points[i] - mean;
        const Eigen::Vector4d row(2.0 * d.x(), 2.0 * d.y(), 2.0 * d.z(), 1.0);
        ata += row * row.transpose();
        atb += row * d.squaredNorm();
      }
      const Eigen::Vector4d sol = ata.ldlt().solve(atb);
      const Vec3 c = sol.head<3>();
      const double r2 = sol[3] + c.squaredNorm();
      if (!sol.allFinite() || !(r2 > 0.0)) return false;
      s.shape = SphereSurface{mean + c, std::sqrt(r2)};
      break;
    }
    case SurfaceType::Cylinder: {
      // The axis is the direction most orthogonal to all normals.
      Mat3 nn = Mat3::Zero();
      for (std::uint32_t i : indices) nn += cloud.normals[i] * cloud.normals[i].transpose();
      const Eigen::SelfAdjointEigenSolver<Mat3> eig(nn);
      const Vec3 axis = eig.eigenvectors().col(0).normalized();
      const Mat3 f = frameFromAxis(axis);
      Vec3 centre;
      double radius = 0.0;
      if (!fitCircle(cloud, indices, mean, f.col(0), f.col(1), centre, radius)) return false;
      s.shape = CylinderSurface{centre, axis, radius};
      break;
    }
    case SurfaceType::Cone:
      if (!initialCone(cloud, indices, mean, s)) return false;
      break;
    case SurfaceType::Torus:
      if (!initialTorus(cloud, indices, mean, s)) return false;
      break;
  }
  if (!validSurface(s)) return false;
  orientByNormals(cloud, indices, s);
  surface = std::move(s);
  return true;
}

}  // namespace csgvox
