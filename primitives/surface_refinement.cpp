#include "primitives/surface_refinement.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/sphere_manifold.h>
#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace csgvox {
namespace {

// Ceres residuals of one point: its orthogonal distance / sigma_p, and the
// components of its scan normal along the surface's two principal tangent
// directions, each divided by sigma_n(kappa) = sqrt(sigma_n^2 + (sigma_p
// kappa)^2): noise moving a point along a surface of curvature kappa tilts the
// surface normal there by sigma_p kappa, so a small hole's normals say little
// about its radius but much about its axis. `guard` keeps square roots
// differentiable at 0 (it is ~1e-20 D^2).
struct PointTerm {
  Vec3 p;                // the point
  Vec3 n;                // its scan normal (unit)
  double wp = 1.0;       // 1 / sigma_p
  double sigmaP = 1.0;   // sigma_p
  double sigmaN = 0.0;   // sigma_n, or 0 to ignore the normal
  double guard = 0.0;

  template <class T>
  T dotN(const T* v) const {
    return T(n.x()) * v[0] + T(n.y()) * v[1] + T(n.z()) * v[2];
  }
  // Weight of a normal component along a direction of curvature kappa.
  template <class T>
  T weight(const T& kappa) const {
    if (sigmaN <= 0.0) return T(0.0);
    using std::sqrt;
    return T(1.0) / sqrt(T(sigmaN * sigmaN) + T(sigmaP * sigmaP) * kappa * kappa);
  }
  // Residuals from the distance and two unit tangent directions t1, t2 of
  // curvatures k1, k2.
  template <class T>
  void write(const T& dist, const T* t1, const T& k1, const T* t2, const T& k2, T* r) const {
    r[0] = T(wp) * dist;
    if (sigmaN <= 0.0) {
      r[1] = r[2] = T(0.0);
      return;
    }
    r[1] = weight(k1) * dotN(t1);
    r[2] = weight(k2) * dotN(t2);
  }
  // Residuals for a surface that curves alike in every direction (plane,
  // sphere) with unit normal s: any two orthonormal tangents will do; they
  // are built from s and a fixed helper axis (the world axis least aligned
  // with the scan normal), so they move smoothly with the parameters.
  template <class T>
  void writeUmbilic(const T& dist, const T* s, const T& kappa, T* r) const {
    if (sigmaN <= 0.0) {
      r[0] = T(wp) * dist;
      r[1] = r[2] = T(0.0);
      return;
    }
    int k = 0;
    for (int i = 1; i < 3; ++i) {
      if (std::abs(n[i]) < std::abs(n[k])) k = i;
    }
    T h[3] = {T(0.0), T(0.0), T(0.0)};
    h[k] = T(1.0);
    T e1[3], e2[3];
    e1[0] = s[1] * h[2] - s[2] * h[1];
    e1[1] = s[2] * h[0] - s[0] * h[2];
    e1[2] = s[0] * h[1] - s[1] * h[0];
    using std::sqrt;
    const T len = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int i = 0; i < 3; ++i) e1[i] /= len;
    e2[0] = s[1] * e1[2] - s[2] * e1[1];
    e2[1] = s[2] * e1[0] - s[0] * e1[2];
    e2[2] = s[0] * e1[1] - s[1] * e1[0];
    write(dist, e1, kappa, e2, kappa, r);
  }
};

template <class T>
void cross(const T* a, const T* b, T* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

struct PlaneResidual {
  PointTerm t;
  template <class T>
  bool operator()(const T* n, const T* d, T* r) const {
    t.writeUmbilic(n[0] * t.p.x() + n[1] * t.p.y() + n[2] * t.p.z() - d[0], n, T(0.0), r);
    return true;
  }
};

// The unit radial direction of w relative to the unit axis a, and the
// distance from the axis.
template <class T>
T radialPart(const T* w, const T* a, T* radial, double guard) {
  const T z = w[0] * a[0] + w[1] * a[1] + w[2] * a[2];
  for (int i = 0; i < 3; ++i) radial[i] = w[i] - z * a[i];
  using std::sqrt;
  const T rho = sqrt(radial[0] * radial[0] + radial[1] * radial[1] + radial[2] * radial[2] + T(guard));
  for (int i = 0; i < 3; ++i) radial[i] /= rho;
  return rho;
}

// The axis passes through base + s0*u + s1*v, with u, v perpendicular to the
// start axis: two parameters for the axis position, none wasted along it.
struct CylinderResidual {
  PointTerm t;
  Vec3 base, u, v;
  template <class T>
  bool operator()(const T* a, const T* s, const T* radius, T* r) const {
    T w[3], radial[3], tangent[3];
    for (int i = 0; i < 3; ++i) w[i] = t.p[i] - (base[i] + s[0] * u[i] + s[1] * v[i]);
    const T rho = radialPart(w, a, radial, t.guard);
    cross(a, radial, tangent);
    t.write(rho - radius[0], a, T(0.0), tangent, T(1.0) / radius[0], r);
    return true;
  }
};

struct ConeResidual {
  PointTerm t;
  template <class T>
  bool operator()(const T* apex, const T* a, const T* angle, T* r) const {
    T w[3], radial[3], tangent[3], generator[3];
    for (int i = 0; i < 3; ++i) w[i] = t.p[i] - apex[i];
    const T z = w[0] * a[0] + w[1] * a[1] + w[2] * a[2];
    const T rho = radialPart(w, a, radial, t.guard);
    using std::cos;
    using std::sin;
    const T c = cos(angle[0]), sn = sin(angle[0]);
    for (int i = 0; i < 3; ++i) generator[i] = sn * radial[i] + c * a[i];
    cross(a, radial, tangent);
    t.write(rho * c - z * sn, generator, T(0.0), tangent, c / rho, r);
    return true;
  }
};

struct SphereResidual {
  PointTerm t;
  template <class T>
  bool operator()(const T* c, const T* radius, T* r) const {
    T w[3];
    for (int i = 0; i < 3; ++i) w[i] = t.p[i] - c[i];
    using std::sqrt;
    const T len = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + T(t.guard));
    T normal[3];
    for (int i = 0; i < 3; ++i) normal[i] = w[i] / len;
    t.writeUmbilic(len - radius[0], normal, T(1.0) / radius[0], r);
    return true;
  }
};

struct TorusResidual {
  PointTerm t;
  template <class T>
  bool operator()(const T* c, const T* a, const T* radii, T* r) const {
    T w[3], radial[3], tangent[3], meridian[3];
    for (int i = 0; i < 3; ++i) w[i] = t.p[i] - c[i];
    const T z = w[0] * a[0] + w[1] * a[1] + w[2] * a[2];
    const T rho = radialPart(w, a, radial, t.guard);
    // From the tube's centre circle to the point.
    T q[3];
    for (int i = 0; i < 3; ++i) q[i] = (rho - radii[0]) * radial[i] + z * a[i];
    using std::abs;
    using std::sqrt;
    const T len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + T(t.guard));
    T normal[3];
    for (int i = 0; i < 3; ++i) normal[i] = q[i] / len;
    cross(a, radial, tangent);
    cross(normal, tangent, meridian);
    const T cosPhi = normal[0] * radial[0] + normal[1] * radial[1] + normal[2] * radial[2];
    const T ring = radii[0] + radii[1] * cosPhi;
    t.write(len - radii[1], meridian, T(1.0) / radii[1], tangent, abs(cosPhi) / ring, r);
    return true;
  }
};

// An even, deterministic subset of at most `count` of the indices.
std::vector<std::uint32_t> evenSubset(std::span<const std::uint32_t> indices, std::size_t count) {
  if (indices.size() <= count) return {indices.begin(), indices.end()};
  std::vector<std::uint32_t> out;
  out.reserve(count);
  for (std::size_t k = 0; k < count; ++k) out.push_back(indices[k * indices.size() / count]);
  return out;
}

Vec3 radialOf(const Vec3& d, const Vec3& axis) {
  Vec3 radial = d - d.dot(axis) * axis;
  const double n = radial.norm();
  return n > 0.0 ? Vec3(radial / n) : Vec3(frameFromAxis(axis).col(0));
}

// Outward normal of the surface at p when the surface is convex (normals
// away from the axis, centre or tube centre); the plane's own normal.
Vec3 convexNormal(const Surface& surface, const Vec3& p) {
  switch (surface.type()) {
    case SurfaceType::Plane: return surface.as<PlaneSurface>()->normal;
    case SurfaceType::Cylinder: {
      const auto& c = *surface.as<CylinderSurface>();
      return radialOf(p - c.axisPoint, c.axisDir);
    }
    case SurfaceType::Cone: {
      const auto& c = *surface.as<ConeSurface>();
      const Vec3 radial = radialOf(p - c.apex, c.axisDir);
      return std::cos(c.halfAngle) * radial - std::sin(c.halfAngle) * c.axisDir;
    }
    case SurfaceType::Sphere: {
      const auto& s = *surface.as<SphereSurface>();
      const Vec3 d = p - s.center;
      const double n = d.norm();
      return n > 0.0 ? Vec3(d / n) : Vec3::UnitZ();
    }
    case SurfaceType::Torus: {
      const auto& t = *surface.as<TorusSurface>();
      const Vec3 tube = t.center + t.majorRadius * radialOf(p - t.center, t.axisDir);
      const Vec3 d = p - tube;
      const double n = d.norm();
      return n > 0.0 ? Vec3(d / n) : radialOf(p - t.center, t.axisDir);
    }
  }
  return Vec3::UnitZ();
}

// Orients the surface as the majority of the points' normals: plane normal
// flipped, or the convexity flag set.
void orientByNormals(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                     Surface& surface) {
  std::size_t agree = 0;
  for (std::uint32_t i : indices) {
    agree += convexNormal(surface, cloud.points[i]).dot(cloud.normals[i]) > 0.0;
  }
  const bool majority = 2 * agree >= indices.size();
  if (auto* plane = std::get_if<PlaneSurface>(&surface.shape)) {
    if (!majority) {
      plane->normal = -plane->normal;
      plane->offset = -plane->offset;
    }
    surface.convex = true;
  } else {
    surface.convex = majority;
  }
}

double rmsDistance(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                   const Surface& surface) {
  if (indices.empty()) return 0.0;
  double sum = 0.0;
  for (std::uint32_t i : indices) sum += std::pow(surfaceDistance(surface, cloud.points[i]), 2);
  return std::sqrt(sum / double(indices.size()));
}

bool validSurface(const Surface& s) {
  switch (s.type()) {
    case SurfaceType::Plane: {
      const auto& p = *s.as<PlaneSurface>();
      return p.normal.allFinite() && std::isfinite(p.offset);
    }
    case SurfaceType::Cylinder: {
      const auto& c = *s.as<CylinderSurface>();
      return c.axisPoint.allFinite() && c.axisDir.allFinite() && c.radius > 0.0 &&
             std::isfinite(c.radius);
    }
    case SurfaceType::Cone: {
      const auto& c = *s.as<ConeSurface>();
      return c.apex.allFinite() && c.axisDir.allFinite() && c.halfAngle > 0.0 &&
             c.halfAngle < 0.5 * std::numbers::pi;
    }
    case SurfaceType::Sphere: {
      const auto& c = *s.as<SphereSurface>();
      return c.center.allFinite() && c.radius > 0.0 && std::isfinite(c.radius);
    }
    case SurfaceType::Torus: {
      const auto& t = *s.as<TorusSurface>();
      return t.center.allFinite() && t.axisDir.allFinite() && t.minorRadius > 0.0 &&
             t.majorRadius >= t.minorRadius && std::isfinite(t.majorRadius);
    }
  }
  return false;
}

Mat3 covarianceOf(const PointCloud& cloud, std::span<const std::uint32_t> indices, Vec3& mean) {
  mean = Vec3::Zero();
  for (std::uint32_t i : indices) mean += cloud.points[i];
  mean /= double(indices.size());
  Mat3 cov = Mat3::Zero();
  for (std::uint32_t i : indices) {
    const Vec3 d = cloud.points[i] - mean;
    cov += d * d.transpose();
  }
  return cov / double(indices.size());
}

// Kasa circle fit in the plane spanned by u, v through `origin`; false when
// the points are collinear in that plane.
bool fitCircle(const PointCloud& cloud, std::span<const std::uint32_t> indices,
               const Vec3& origin, const Vec3& u, const Vec3& v, Vec3& centre, double& radius) {
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
  Vec3 nmean = Vec3::Zero();
  for (std::uint32_t i : indices) nmean += cloud.normals[i];
  nmean /= double(indices.size());
  Mat3 cov = Mat3::Zero();
  for (std::uint32_t i : indices) {
    const Vec3 d = cloud.normals[i] - nmean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
  Vec3 axis = eig.eigenvectors().col(0).normalized();
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

Vec3 surfaceNormal(const Surface& surface, const Vec3& p) {
  const Vec3 n = convexNormal(surface, p);
  return surface.convex ? n : Vec3(-n);
}

bool initialSurface(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                    SurfaceType type, Surface& surface) {
  if (indices.size() < 6) return false;
  Vec3 mean;
  const Mat3 cov = covarianceOf(cloud, indices, mean);
  Surface s;
  s.inliers.assign(indices.begin(), indices.end());
  switch (type) {
    case SurfaceType::Plane: {
      const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
      const Vec3 n = eig.eigenvectors().col(0).normalized();
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

PointFit pointFit(const Surface& surface, const Vec3& p, const Vec3& n, const FitScales& scales) {
  const PointTerm t{p, n, 1.0 / scales.position, scales.position, scales.normal, 1e-300};
  double r[3] = {0.0, 0.0, 0.0};
  switch (surface.type()) {
    case SurfaceType::Plane: {
      const auto& s = *surface.as<PlaneSurface>();
      const double a[3] = {s.normal.x(), s.normal.y(), s.normal.z()};
      PlaneResidual{t}(a, &s.offset, r);
      break;
    }
    case SurfaceType::Cylinder: {
      const auto& s = *surface.as<CylinderSurface>();
      const double a[3] = {s.axisDir.x(), s.axisDir.y(), s.axisDir.z()}, off[2] = {0.0, 0.0};
      CylinderResidual{t, s.axisPoint, Vec3::Zero(), Vec3::Zero()}(a, off, &s.radius, r);
      break;
    }
    case SurfaceType::Cone: {
      const auto& s = *surface.as<ConeSurface>();
      const double apex[3] = {s.apex.x(), s.apex.y(), s.apex.z()};
      const double a[3] = {s.axisDir.x(), s.axisDir.y(), s.axisDir.z()};
      ConeResidual{t}(apex, a, &s.halfAngle, r);
      break;
    }
    case SurfaceType::Sphere: {
      const auto& s = *surface.as<SphereSurface>();
      const double c[3] = {s.center.x(), s.center.y(), s.center.z()};
      SphereResidual{t}(c, &s.radius, r);
      break;
    }
    case SurfaceType::Torus: {
      const auto& s = *surface.as<TorusSurface>();
      const double c[3] = {s.center.x(), s.center.y(), s.center.z()};
      const double a[3] = {s.axisDir.x(), s.axisDir.y(), s.axisDir.z()};
      const double radii[2] = {s.majorRadius, s.minorRadius};
      TorusResidual{t}(c, a, radii, r);
      break;
    }
  }
  PointFit fit;
  fit.distance = std::abs(r[0]) * scales.position;
  fit.normal2 = r[1] * r[1] + r[2] * r[2];
  fit.cosine = surfaceNormal(surface, p).dot(n);
  return fit;
}

bool pointOnSurface(const Surface& surface, const Vec3& p, const Vec3& n, const FitScales& scales,
                    double epsilon, double threshold) {
  if (surfaceDistance(surface, p) > epsilon) return false;  // cheap test first
  const PointFit fit = pointFit(surface, p, n, scales);
  return fit.cosine >= threshold && (scales.normal <= 0.0 || fit.normal2 <= kNormalChi2);
}

FitScales fitScales(const DetectionResult& result, const RefineOptions& options) {
  FitScales scales;
  scales.position = std::max(result.noise, 0.02 * result.epsilon);
  if (!(scales.position > 0.0)) scales.position = 1e-6 * std::max(result.diagonal, 1e-300);
  scales.normal = options.useNormals ? std::max(result.normalNoise, 0.02) : 0.0;
  scales.loss = options.lossScale * result.epsilon;
  if (!(scales.loss > 0.0)) scales.loss = 3.0 * scales.position;
  return scales;
}

double fitSurface(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                  Surface& surface, const FitScales& scales, const RefineOptions& options) {
  if (!(scales.position > 0.0) || !(scales.loss > 0.0) || !(scales.normal >= 0.0)) {
    throw std::invalid_argument("fitSurface: scales must be positive");
  }
  const std::vector<std::uint32_t> pts = evenSubset(indices, std::max<std::size_t>(16, options.maxFitPoints));
  if (pts.size() < 4) return -1.0;
  Vec3 mean;
  const Mat3 cov = covarianceOf(cloud, pts, mean);
  const double extent2 = std::max(cov.trace(), 1e-300);
  const double guard = 1e-20 * extent2;
  const double minLength = 1e-6 * std::sqrt(extent2);  // radii stay positive
  const bool normals = scales.normal > 0.0 && cloud.hasNormals();
  const auto term = [&](std::uint32_t i) {
    return PointTerm{cloud.points[i], normals ? cloud.normals[i] : Vec3::Zero(),
                     1.0 / scales.position, scales.position, normals ? scales.normal : 0.0, guard};
  };

  ceres::Problem::Options problemOptions;
  problemOptions.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problemOptions.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problemOptions);
  ceres::HuberLoss loss(scales.loss / scales.position);

  Surface out = surface;
  // Parameter blocks (at most three), in doubles.
  double a[3] = {0, 0, 1}, b[3] = {0, 0, 0}, c[2] = {0, 0}, d[2] = {0, 0};
  Vec3 base = Vec3::Zero(), u = Vec3::UnitX(), v = Vec3::UnitY();
  const auto setUnit = [](double* dst, const Vec3& src) {
    const Vec3 n = src.normalized();
    dst[0] = n.x(), dst[1] = n.y(), dst[2] = n.z();
  };
  switch (surface.type()) {
    case SurfaceType::Plane: {
      const auto& s = *surface.as<PlaneSurface>();
      setUnit(a, s.normal);
      d[0] = s.offset;
      for (std::uint32_t i : pts) {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<PlaneResidual, 3, 3, 1>(new PlaneResidual{term(i)}),
            &loss, a, d);
      }
      problem.SetManifold(a, new ceres::SphereManifold<3>());
      break;
    }
    case SurfaceType::Cylinder: {
      const auto& s = *surface.as<CylinderSurface>();
      setUnit(a, s.axisDir);
      const Vec3 axis(a[0], a[1], a[2]);
      base = s.axisPoint + (mean - s.axisPoint).dot(axis) * axis;
      const Mat3 f = frameFromAxis(axis);
      u = f.col(0), v = f.col(1);
      d[0] = std::max(s.radius, 2.0 * minLength);
      for (std::uint32_t i : pts) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CylinderResidual, 3, 3, 2, 1>(
                                     new CylinderResidual{term(i), base, u, v}),
                                 &loss, a, c, d);
      }
      problem.SetManifold(a, new ceres::SphereManifold<3>());
      problem.SetParameterLowerBound(d, 0, minLength);
      break;
    }
    case SurfaceType::Cone: {
      const auto& s = *surface.as<ConeSurface>();
      b[0] = s.apex.x(), b[1] = s.apex.y(), b[2] = s.apex.z();
      setUnit(a, s.axisDir);
      d[0] = std::clamp(s.halfAngle, 2e-3, 0.5 * std::numbers::pi - 2e-3);
      for (std::uint32_t i : pts) {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<ConeResidual, 3, 3, 3, 1>(new ConeResidual{term(i)}),
            &loss, b, a, d);
      }
      problem.SetManifold(a, new ceres::SphereManifold<3>());
      problem.SetParameterLowerBound(d, 0, 1e-3);
      problem.SetParameterUpperBound(d, 0, 0.5 * std::numbers::pi - 1e-3);
      break;
    }
    case SurfaceType::Sphere: {
      const auto& s = *surface.as<SphereSurface>();
      b[0] = s.center.x(), b[1] = s.center.y(), b[2] = s.center.z();
      d[0] = std::max(s.radius, 2.0 * minLength);
      for (std::uint32_t i : pts) {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<SphereResidual, 3, 3, 1>(new SphereResidual{term(i)}),
            &loss, b, d);
      }
      problem.SetParameterLowerBound(d, 0, minLength);
      break;
    }
    case SurfaceType::Torus: {
      const auto& s = *surface.as<TorusSurface>();
      b[0] = s.center.x(), b[1] = s.center.y(), b[2] = s.center.z();
      setUnit(a, s.axisDir);
      d[0] = std::max(s.majorRadius, 2.0 * minLength), d[1] = std::max(s.minorRadius, 2.0 * minLength);
      for (std::uint32_t i : pts) {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<TorusResidual, 3, 3, 3, 2>(new TorusResidual{term(i)}),
            &loss, b, a, d);
      }
      problem.SetManifold(a, new ceres::SphereManifold<3>());
      problem.SetParameterLowerBound(d, 0, minLength);
      problem.SetParameterLowerBound(d, 1, minLength);
      break;
    }
  }

  ceres::Solver::Options solverOptions;
  solverOptions.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solverOptions.max_num_iterations = options.maxIterations;
  solverOptions.num_threads = 1;
  solverOptions.logging_type = ceres::SILENT;
  solverOptions.minimizer_progress_to_stdout = false;
  solverOptions.function_tolerance = 1e-12;
  solverOptions.parameter_tolerance = 1e-12;
  solverOptions.gradient_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(solverOptions, &problem, &summary);

  const Vec3 axis = Vec3(a[0], a[1], a[2]).normalized();
  switch (surface.type()) {
    case SurfaceType::Plane: out.shape = PlaneSurface{axis, d[0]}; break;
    case SurfaceType::Cylinder: {
      const Vec3 point = base + c[0] * u + c[1] * v;
      // Keep the axis point next to the inliers.
      out.shape = CylinderSurface{point + (mean - point).dot(axis) * axis, axis, d[0]};
      break;
    }
    case SurfaceType::Cone: out.shape = ConeSurface{Vec3(b[0], b[1], b[2]), axis, d[0]}; break;
    case SurfaceType::Sphere: out.shape = SphereSurface{Vec3(b[0], b[1], b[2]), d[0]}; break;
    case SurfaceType::Torus: {
      const Vec3 centre(b[0], b[1], b[2]);
      out.shape = TorusSurface{centre, axis, d[0], d[1]};
      break;
    }
  }
  if (!validSurface(out)) return -1.0;
  orientByNormals(cloud, indices, out);
  const double rms = rmsDistance(cloud, indices, out);
  if (!std::isfinite(rms)) return -1.0;
  out.rms = rms;
  surface = std::move(out);
  return rms;
}

namespace {

// Points binned into cubic cells of a given side. Two cells are adjacent
// when they touch (26-neighbourhood): the 3D analogue of the bitmap on which
// RANSAC (Schnabel et al. 2007, CGAL's cluster epsilon) decides that the
// points of a shape form one connected patch.
class CellGrid {
 public:
  using Key = std::array<std::int64_t, 3>;

  CellGrid(const PointCloud& cloud, std::span<const std::uint32_t> indices, double side)
      : side_(side) {
    for (std::uint32_t i : indices) cells_[keyOf(cloud.points[i])].push_back(i);
  }

  Key keyOf(const Vec3& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() / side_)),
            static_cast<std::int64_t>(std::floor(p.y() / side_)),
            static_cast<std::int64_t>(std::floor(p.z() / side_))};
  }

  // Calls visit(key, points) for the occupied cells adjacent to (or equal to) the cell k.
  template <class Visit>
  void forAdjacent(const Key& k, Visit&& visit) const {
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(Key{k[0] + dx, k[1] + dy, k[2] + dz});
          if (it != cells_.end()) visit(it->first, it->second);
        }
      }
    }
  }

  // True when the cell of p is occupied or adjacent to an occupied one.
  bool touches(const Vec3& p) const {
    bool any = false;
    forAdjacent(keyOf(p), [&](const Key&, const std::vector<std::uint32_t>&) { any = true; });
    return any;
  }

  // Marks in `isolated` the points of the connected groups of cells holding
  // fewer than `minPoints` points, when another group holds at least that many.
  void markSmallGroups(std::size_t minPoints, std::vector<char>& isolated) const {
    std::unordered_map<Key, std::size_t, KeyHash> slot;
    std::vector<const Key*> keys;
    std::vector<const std::vector<std::uint32_t>*> points;
    for (const auto& [key, pts] : cells_) {
      slot.emplace(key, keys.size());
      keys.push_back(&key);
      points.push_back(&pts);
    }
    std::vector<std::size_t> parent(keys.size());
    for (std::size_t c = 0; c < keys.size(); ++c) parent[c] = c;
    const auto root = [&](std::size_t c) {
      while (parent[c] != c) c = parent[c] = parent[parent[c]];
      return c;
    };
    for (std::size_t c = 0; c < keys.size(); ++c) {
      forAdjacent(*keys[c], [&](const Key& other, const std::vector<std::uint32_t>&) {
        const std::size_t x = root(c), y = root(slot.at(other));
        if (x != y) parent[std::max(x, y)] = std::min(x, y);
      });
    }
    std::vector<std::size_t> size(keys.size(), 0);
    for (std::size_t c = 0; c < keys.size(); ++c) size[root(c)] += points[c]->size();
    // Without a patch of that size there is nothing to be apart from: the
    // surface stands or falls by its count alone.
    if (keys.empty() || *std::max_element(size.begin(), size.end()) < minPoints) return;
    for (std::size_t c = 0; c < keys.size(); ++c) {
      if (size[root(c)] >= minPoints) continue;
      for (std::uint32_t i : *points[c]) isolated[i] = 1;
    }
  }

 private:
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::size_t h = 1469598103934665603ull;
      for (std::int64_t v : k) h = (h ^ static_cast<std::size_t>(v)) * 1099511628211ull;
      return h;
    }
  };
  double side_;
  std::unordered_map<Key, std::vector<std::uint32_t>, KeyHash> cells_;
};

}  // namespace

void reassignPoints(const PointCloud& cloud, DetectionResult& result, std::size_t minPoints,
                    bool connectedPatches) {
  const double eps = result.epsilon;
  const double cell = result.clusterEpsilon;
  const FitScales scales = fitScales(result);
  const double threshold = result.normalThreshold;
  std::vector<Surface>& surfaces = result.surfaces;
  std::vector<char> alive(surfaces.size(), 1);
  result.assignment.assign(cloud.size(), -1);
  // The surface point i fits best among the live ones that `allowed` accepts, or -1.
  const auto bestSurface = [&](std::size_t i, const auto& allowed) {
    const Vec3& p = cloud.points[i];
    int best = -1;
    double bestScore = std::numeric_limits<double>::infinity();
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      if (!alive[s] || surfaceDistance(surfaces[s], p) > eps || !allowed(s)) continue;
      const PointFit fit = pointFit(surfaces[s], p, cloud.normals[i], scales);
      if (fit.cosine < threshold || (scales.normal > 0.0 && fit.normal2 > kNormalChi2)) continue;
      const double score = std::pow(fit.distance / scales.position, 2) + fit.normal2;
      if (score < bestScore) {
        best = int(s);
        bestScore = score;
      }
    }
    return best;
  };
  for (int round = 0; round < 8; ++round) {
    tbb::parallel_for(std::size_t(0), cloud.size(), [&](std::size_t i) {
      result.assignment[i] = bestSurface(i, [](std::size_t) { return true; });
    });
    // The distance test alone also accepts the noise tails of neighbouring
    // surfaces that reach into this surface's band far from its patch (the
    // outer points of a coaxial cylinder of a slightly smaller radius, all
    // along it). Detection accepted a surface only as a connected patch of
    // at least minPoints points (cluster epsilon apart); points that form
    // smaller components of a surface are not on its patch, and go to the
    // best surface whose patch they touch, if any.
    if (connectedPatches && cell > 0.0) {
      std::vector<std::vector<std::uint32_t>> members(surfaces.size());
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (result.assignment[i] >= 0) {
          members[std::size_t(result.assignment[i])].push_back(std::uint32_t(i));
        }
      }
      std::vector<char> isolated(cloud.size(), 0);
      tbb::parallel_for(std::size_t(0), surfaces.size(), [&](std::size_t s) {
        CellGrid(cloud, members[s], cell).markSmallGroups(minPoints, isolated);
      });
      std::vector<std::uint32_t> moved;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (isolated[i]) moved.push_back(std::uint32_t(i));
      }
      if (!moved.empty()) {
        std::vector<std::vector<std::uint32_t>> kept(surfaces.size());
        for (std::size_t s = 0; s < surfaces.size(); ++s) {
          std::copy_if(members[s].begin(), members[s].end(), std::back_inserter(kept[s]),
                       [&](std::uint32_t i) { return !isolated[i]; });
        }
        std::vector<CellGrid> grids;
        grids.reserve(surfaces.size());
        for (std::size_t s = 0; s < surfaces.size(); ++s) {
          grids.emplace_back(cloud, kept[s], cell);
        }
        tbb::parallel_for(std::size_t(0), moved.size(), [&](std::size_t k) {
          const std::uint32_t i = moved[k];
          const int from = result.assignment[i];
          result.assignment[i] = bestSurface(i, [&](std::size_t s) {
            return int(s) != from && grids[s].touches(cloud.points[i]);
          });
        });
      }
    }
    std::vector<std::size_t> counts(surfaces.size(), 0);
    for (int s : result.assignment) {
      if (s >= 0) ++counts[std::size_t(s)];
    }
    bool dropped = false;
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      if (alive[s] && counts[s] < minPoints) {
        alive[s] = 0;
        dropped = true;
      }
    }
    if (!dropped) break;
  }
  // Compact: keep the live surfaces in order.
  std::vector<int> newIndex(surfaces.size(), -1);
  std::vector<Surface> kept;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    if (!alive[s]) continue;
    newIndex[s] = int(kept.size());
    kept.push_back(std::move(surfaces[s]));
    kept.back().inliers.clear();
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    int& s = result.assignment[i];
    if (s >= 0) s = newIndex[std::size_t(s)];
    if (s >= 0) kept[std::size_t(s)].inliers.push_back(std::uint32_t(i));
  }
  surfaces = std::move(kept);
  result.centroids.assign(surfaces.size(), Vec3::Zero());
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    Surface& surf = surfaces[s];
    Vec3 sum = Vec3::Zero();
    for (std::uint32_t i : surf.inliers) sum += cloud.points[i];
    if (!surf.inliers.empty()) result.centroids[s] = sum / double(surf.inliers.size());
    surf.rms = rmsDistance(cloud, surf.inliers, surf);
  }
}

namespace {

// Fits every surface on its inliers (in parallel); surfaces whose fit
// degenerates keep their parameters.
void fitAll(const PointCloud& cloud, DetectionResult& result, const RefineOptions& options) {
  const FitScales scales = fitScales(result, options);
  // One task per surface: the fits differ widely in cost (largest surfaces first).
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, result.surfaces.size(), 1),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t s = range.begin(); s != range.end(); ++s) {
          Surface& surf = result.surfaces[s];
          Surface trial = surf;
          if (fitSurface(cloud, surf.inliers, trial, scales, options) >= 0.0) surf = std::move(trial);
        }
      },
      tbb::simple_partitioner());
}

// Removes surfaces whose inliers other surfaces explain: a duplicate, a
// plane strip cut from a large cylinder, or one flexible surface (a torus,
// a sphere) spanning several true ones once those are found. Of the
// redundant surfaces, the one the others fit best relative to itself goes
// first (ties: the more complex type), then the test is repeated.
void removeRedundant(const PointCloud& cloud, DetectionResult& result, const RefineOptions& options) {
  std::vector<Surface>& surfaces = result.surfaces;
  const double eps = result.epsilon;
  std::vector<char> alive(surfaces.size(), 1);
  const auto complexityOf = [](SurfaceType t) {
    switch (t) {
      case SurfaceType::Plane: return 0;
      case SurfaceType::Sphere: return 1;
      case SurfaceType::Cylinder: return 2;
      case SurfaceType::Cone: return 3;
      case SurfaceType::Torus: return 4;
    }
    return 5;
  };
  const FitScales scales = fitScales(result, options);
  const double cap = std::pow(eps / scales.position, 2) + kNormalChi2;
  // Scaled squared residual of point i on surface t, or the cap when it is not on it.
  const auto score = [&](std::size_t t, std::uint32_t i) {
    const Vec3& p = cloud.points[i];
    if (surfaceDistance(surfaces[t], p) > eps) return cap;
    const PointFit fit = pointFit(surfaces[t], p, cloud.normals[i], scales);
    if (fit.cosine < result.normalThreshold || (scales.normal > 0.0 && fit.normal2 > kNormalChi2)) {
      return cap;
    }
    return std::pow(fit.distance / scales.position, 2) + fit.normal2;
  };
  // The scores of every inlier on its own surface and on every other surface
  // that explains it (below the cap), computed once in parallel over the
  // points; the surfaces do not change below, so each round only looks them up.
  std::vector<std::size_t> first(surfaces.size() + 1, 0);
  for (std::size_t s = 0; s < surfaces.size(); ++s) first[s + 1] = first[s] + surfaces[s].inliers.size();
  std::vector<std::uint32_t> owner(first.back());
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    std::fill(owner.begin() + std::ptrdiff_t(first[s]), owner.begin() + std::ptrdiff_t(first[s + 1]),
              std::uint32_t(s));
  }
  using Entry = std::pair<std::uint32_t, double>;  // surface, score
  std::vector<std::vector<Entry>> near(first.back());
  tbb::parallel_for(std::size_t(0), first.back(), [&](std::size_t k) {
    const std::uint32_t i = surfaces[owner[k]].inliers[k - first[owner[k]]];
    for (std::size_t t = 0; t < surfaces.size(); ++t) {
      const double v = score(t, i);
      if (v < cap || t == owner[k]) near[k].emplace_back(std::uint32_t(t), v);
    }
  });
  while (true) {
    std::vector<double> excess(surfaces.size(), -1e300);
    tbb::parallel_for(std::size_t(0), surfaces.size(), [&](std::size_t s) {
      if (!alive[s] || surfaces[s].inliers.empty()) return;
      std::size_t explained = 0;
      double sum = 0.0;
      for (std::size_t k = first[s]; k < first[s + 1]; ++k) {
        double self = cap, other = cap;
        for (const auto& [t, v] : near[k]) {
          if (t == s) {
            self = v;
          } else if (alive[t]) {
            other = std::min(other, v);
          }
        }  // surfaces missing from near[k] score the cap
        explained += other < cap;
        sum += self - other;
      }
      // Redundant: others explain most of its points, and about as well.
      const double mean = sum / double(surfaces[s].inliers.size());
      if (double(explained) >= options.redundantFraction * double(surfaces[s].inliers.size()) &&
          mean >= -0.5) {
        excess[s] = mean;
      }
    });
    int worst = -1;
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      if (excess[s] <= -1e299) continue;
      if (worst < 0) {
        worst = int(s);
        continue;
      }
      const std::size_t w = std::size_t(worst);
      const double tie = 0.25;  // in units of the scaled squared residual
      const bool better =
          excess[s] > excess[w] + tie ||
          (excess[s] > excess[w] - tie &&
           (complexityOf(surfaces[s].type()) > complexityOf(surfaces[w].type()) ||
            (complexityOf(surfaces[s].type()) == complexityOf(surfaces[w].type()) &&
             surfaces[s].inliers.size() < surfaces[w].inliers.size())));
      if (better) worst = int(s);
    }
    if (worst < 0) break;
    alive[std::size_t(worst)] = 0;
  }
  std::vector<Surface> kept;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    if (alive[s]) kept.push_back(std::move(surfaces[s]));
  }
  surfaces = std::move(kept);
}

// Sorts surfaces by inlier count (largest first, stable) and renumbers the assignment.
void sortBySize(DetectionResult& result) {
  const std::size_t n = result.surfaces.size();
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return result.surfaces[x].inliers.size() > result.surfaces[y].inliers.size();
  });
  std::vector<int> newIndex(n);
  std::vector<Surface> surfaces;
  std::vector<Vec3> centroids;
  for (std::size_t k = 0; k < n; ++k) {
    newIndex[order[k]] = int(k);
    surfaces.push_back(std::move(result.surfaces[order[k]]));
    if (result.centroids.size() == n) centroids.push_back(result.centroids[order[k]]);
  }
  for (int& s : result.assignment) {
    if (s >= 0) s = newIndex[std::size_t(s)];
  }
  result.surfaces = std::move(surfaces);
  if (centroids.size() == n) result.centroids = std::move(centroids);
}

}  // namespace

void refineSurfaces(const PointCloud& cloud, DetectionResult& result, const RefineOptions& options) {
  if (result.assignment.size() != cloud.size()) {
    throw std::invalid_argument("refineSurfaces: the detection result belongs to another cloud");
  }
  if (result.surfaces.empty()) return;
  if (!cloud.hasNormals()) throw std::invalid_argument("refineSurfaces needs one normal per point");
  if (!(result.epsilon > 0.0)) {
    throw std::invalid_argument("refineSurfaces: the detection result has no epsilon");
  }
  fitAll(cloud, result, options);
  if (options.removeRedundant) removeRedundant(cloud, result, options);
  if (options.reassign) {
    reassignPoints(cloud, result, std::max<std::size_t>(1, result.minPoints),
                   options.connectedPatches);
    fitAll(cloud, result, options);
  }
  // Final bookkeeping: rms and centroids on the final inliers.
  result.centroids.assign(result.surfaces.size(), Vec3::Zero());
  for (std::size_t s = 0; s < result.surfaces.size(); ++s) {
    Surface& surf = result.surfaces[s];
    Vec3 sum = Vec3::Zero();
    for (std::uint32_t i : surf.inliers) sum += cloud.points[i];
    if (!surf.inliers.empty()) result.centroids[s] = sum / double(surf.inliers.size());
    surf.rms = rmsDistance(cloud, surf.inliers, surf);
  }
  std::fill(result.assignment.begin(), result.assignment.end(), -1);
  for (std::size_t s = 0; s < result.surfaces.size(); ++s) {
    for (std::uint32_t i : result.surfaces[s].inliers) result.assignment[i] = int(s);
  }
  sortBySize(result);
  if (result.surfaces.empty() && result.status == DetectionResult::Status::Ok) {
    result.status = DetectionResult::Status::NoSurfaces;
    result.message = "no surface kept enough points after refinement";
  }
}

}  // namespace csgvox
