// Surface fitting: the Ceres residuals of a point on each surface type,
// robust least squares of a surface on its inliers, and the per-point fit
// measures that assignment uses.

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/sphere_manifold.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <unordered_map>
#include <variant>
#include <vector>

#include "core/principal_axes.h"
#include "primitives/surface_fit.h"
#include "primitives/surface_fit_internal.h"

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
  Vec3 p;               // the point
  Vec3 n;               // its scan normal (unit)
  double wp = 1.0;      // 1 / sigma_p
  double sigmaP = 1.0;  // sigma_p
  double sigmaN = 0.0;  // sigma_n, or 0 to ignore the normal
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
  const T rho =
      sqrt(radial[0] * radial[0] + radial[1] * radial[1] + radial[2] * radial[2] + T(guard));
  for (int i = 0; i < 3; ++i) radial[i] /= rho;
  return rho;
}

// Of point p relative to `origin` on the unit axis a: its height z along the
// axis, its unit radial direction, the unit tangent a x radial of the circle
// about the axis through it and (returned) its distance from the axis.
template <class T>
T aroundAxis(const Vec3& p, const T* origin, const T* a, T& z, T* radial, T* tangent,
             double guard) {
  T w[3];
  for (int i = 0; i < 3; ++i) w[i] = p[i] - origin[i];
  z = w[0] * a[0] + w[1] * a[1] + w[2] * a[2];
  const T rho = radialPart(w, a, radial, guard);
  cross(a, radial, tangent);
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
    T z, radial[3], tangent[3], generator[3];
    const T rho = aroundAxis(t.p, apex, a, z, radial, tangent, t.guard);
    using std::cos;
    using std::sin;
    const T c = cos(angle[0]), sn = sin(angle[0]);
    for (int i = 0; i < 3; ++i) generator[i] = sn * radial[i] + c * a[i];
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
    T z, radial[3], tangent[3], meridian[3];
    const T rho = aroundAxis(t.p, c, a, z, radial, tangent, t.guard);
    // From the tube's centre circle to the point.
    T q[3];
    for (int i = 0; i < 3; ++i) q[i] = (rho - radii[0]) * radial[i] + z * a[i];
    using std::abs;
    using std::sqrt;
    const T len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + T(t.guard));
    T normal[3];
    for (int i = 0; i < 3; ++i) normal[i] = q[i] / len;
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
    case SurfaceType::Plane:
      return surface.as<PlaneSurface>()->normal;
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

// The parameter blocks of one surface fit (in doubles, as Ceres wants them)
// and the problem over them.
class SurfaceFit {
 public:
  SurfaceFit(const FitScales& scales, const Vec3& mean, double minLength)
      : loss_(scales.loss / scales.position), mean_(mean), minLength_(minLength) {
    ceres::Problem::Options problemOptions;
    problemOptions.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problemOptions.manifold_ownership = ceres::TAKE_OWNERSHIP;
    problem_ = std::make_unique<ceres::Problem>(problemOptions);
  }

  // Starts the blocks at `surface` and adds one residual per point.
  template <class Term>
  void build(const Surface& surface, std::span<const std::uint32_t> pts, const Term& term) {
    ceres::Problem& problem = *problem_;
    const Vec3& mean = mean_;
    const double minLength = minLength_;
    const auto setUnit = [](double* dst, const Vec3& src) {
      const Vec3 n = src.normalized();
      dst[0] = n.x(), dst[1] = n.y(), dst[2] = n.z();
    };
    switch (surface.type()) {
      case SurfaceType::Plane: {
        const auto& s = *surface.as<PlaneSurface>();
        setUnit(a_, s.normal);
        d_[0] = s.offset;
        for (std::uint32_t i : pts) {
          problem.AddResidualBlock(
              new ceres::AutoDiffCostFunction<PlaneResidual, 3, 3, 1>(new PlaneResidual{term(i)}),
              &loss_, a_, d_);
        }
        problem.SetManifold(a_, new ceres::SphereManifold<3>());
        break;
      }
      case SurfaceType::Cylinder: {
        const auto& s = *surface.as<CylinderSurface>();
        setUnit(a_, s.axisDir);
        const Vec3 axis(a_[0], a_[1], a_[2]);
        base_ = s.axisPoint + (mean - s.axisPoint).dot(axis) * axis;
        const Mat3 f = frameFromAxis(axis);
        u_ = f.col(0), v_ = f.col(1);
        d_[0] = std::max(s.radius, 2.0 * minLength);
        for (std::uint32_t i : pts) {
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CylinderResidual, 3, 3, 2, 1>(
                                       new CylinderResidual{term(i), base_, u_, v_}),
                                   &loss_, a_, c_, d_);
        }
        problem.SetManifold(a_, new ceres::SphereManifold<3>());
        problem.SetParameterLowerBound(d_, 0, minLength);
        break;
      }
      case SurfaceType::Cone: {
        const auto& s = *surface.as<ConeSurface>();
        b_[0] = s.apex.x(), b_[1] = s.apex.y(), b_[2] = s.apex.z();
        setUnit(a_, s.axisDir);
        d_[0] = std::clamp(s.halfAngle, 2e-3, 0.5 * std::numbers::pi - 2e-3);
        for (std::uint32_t i : pts) {
          problem.AddResidualBlock(
              new ceres::AutoDiffCostFunction<ConeResidual, 3, 3, 3, 1>(new ConeResidual{term(i)}),
              &loss_, b_, a_, d_);
        }
        problem.SetManifold(a_, new ceres::SphereManifold<3>());
        problem.SetParameterLowerBound(d_, 0, 1e-3);
        problem.SetParameterUpperBound(d_, 0, 0.5 * std::numbers::pi - 1e-3);
        break;
      }
      case SurfaceType::Sphere: {
        const auto& s = *surface.as<SphereSurface>();
        b_[0] = s.center.x(), b_[1] = s.center.y(), b_[2] = s.center.z();
        d_[0] = std::max(s.radius, 2.0 * minLength);
        for (std::uint32_t i : pts) {
          problem.AddResidualBlock(
              new ceres::AutoDiffCostFunction<SphereResidual, 3, 3, 1>(new SphereResidual{term(i)}),
              &loss_, b_, d_);
        }
        problem.SetParameterLowerBound(d_, 0, minLength);
        break;
      }
      case SurfaceType::Torus: {
        const auto& s = *surface.as<TorusSurface>();
        b_[0] = s.center.x(), b_[1] = s.center.y(), b_[2] = s.center.z();
        setUnit(a_, s.axisDir);
        d_[0] = std::max(s.majorRadius, 2.0 * minLength),
        d_[1] = std::max(s.minorRadius, 2.0 * minLength);
        for (std::uint32_t i : pts) {
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TorusResidual, 3, 3, 3, 2>(
                                       new TorusResidual{term(i)}),
                                   &loss_, b_, a_, d_);
        }
        problem.SetManifold(a_, new ceres::SphereManifold<3>());
        problem.SetParameterLowerBound(d_, 0, minLength);
        problem.SetParameterLowerBound(d_, 1, minLength);
        break;
      }
    }
  }

  // Runs the solver for at most `iterations` iterations.
  void solve(int iterations) {
    ceres::Solver::Options solverOptions;
    solverOptions.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    solverOptions.max_num_iterations = iterations;
    solverOptions.num_threads = 1;
    solverOptions.logging_type = ceres::SILENT;
    solverOptions.minimizer_progress_to_stdout = false;
    solverOptions.function_tolerance = 1e-12;
    solverOptions.parameter_tolerance = 1e-12;
    solverOptions.gradient_tolerance = 1e-14;
    // On points at their fitted surface to the last bits (a clean scan read
    // from float coordinates), every step fails by rounding and the solver
    // shrinks its trust region from 1e4 down to Ceres' 1e-32 before it stops:
    // 15-20 iterations of 3000-5000 residuals, none of which moves the
    // parameters. Below this radius a step changes nothing a fit could use.
    solverOptions.min_trust_region_radius = 1e-9;
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions, problem_.get(), &summary);
  }

  // `surface` with the fitted parameters.
  Surface result(const Surface& surface) const {
    Surface out = surface;
    const Vec3& mean = mean_;
    const Vec3 axis = Vec3(a_[0], a_[1], a_[2]).normalized();
    switch (surface.type()) {
      case SurfaceType::Plane:
        out.shape = PlaneSurface{axis, d_[0]};
        break;
      case SurfaceType::Cylinder: {
        const Vec3 point = base_ + c_[0] * u_ + c_[1] * v_;
        // Keep the axis point next to the inliers.
        out.shape = CylinderSurface{point + (mean - point).dot(axis) * axis, axis, d_[0]};
        break;
      }
      case SurfaceType::Cone:
        out.shape = ConeSurface{Vec3(b_[0], b_[1], b_[2]), axis, d_[0]};
        break;
      case SurfaceType::Sphere:
        out.shape = SphereSurface{Vec3(b_[0], b_[1], b_[2]), d_[0]};
        break;
      case SurfaceType::Torus: {
        const Vec3 centre(b_[0], b_[1], b_[2]);
        out.shape = TorusSurface{centre, axis, d_[0], d_[1]};
        break;
      }
    }
    return out;
  }

 private:
  // Parameter blocks (at most three per type): a unit axis or normal, a point,
  // an axis offset, sizes.
  double a_[3] = {0, 0, 1}, b_[3] = {0, 0, 0}, c_[2] = {0, 0}, d_[2] = {0, 0};
  // The cylinder's axis passes through base_ + c_[0] u_ + c_[1] v_.
  Vec3 base_ = Vec3::Zero(), u_ = Vec3::UnitX(), v_ = Vec3::UnitY();
  ceres::HuberLoss loss_;
  std::unique_ptr<ceres::Problem> problem_;
  Vec3 mean_;
  double minLength_;
};

}  // namespace

namespace surface_fit_detail {

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

}  // namespace surface_fit_detail

using namespace surface_fit_detail;

int parameterCount(SurfaceType type) {
  static constexpr std::array<int, 5> kCounts{3, 5, 6, 4, 7};  // in SurfaceType's order
  return kCounts[static_cast<std::size_t>(type)];
}

bool plausibleSurface(const Surface& s, double diag) {
  constexpr double kMinAngle = 2.0 * std::numbers::pi / 180.0;
  switch (s.type()) {
    case SurfaceType::Plane:
      return true;
    case SurfaceType::Cylinder:
      return s.as<CylinderSurface>()->radius <= diag;
    case SurfaceType::Cone: {
      const double a = s.as<ConeSurface>()->halfAngle;
      return a >= kMinAngle && a <= 0.5 * std::numbers::pi - kMinAngle;
    }
    case SurfaceType::Sphere:
      return s.as<SphereSurface>()->radius <= diag;
    case SurfaceType::Torus: {
      const auto& t = *s.as<TorusSurface>();
      return t.majorRadius <= diag && t.minorRadius <= t.majorRadius;
    }
  }
  return false;
}

bool plausibleSurface(const Surface& s, double diag, const PointCloud& cloud,
                      std::span<const std::uint32_t> indices) {
  if (!plausibleSurface(s, diag)) return false;
  const auto* cone = s.as<ConeSurface>();
  if (cone == nullptr || indices.empty()) return true;
  // A cone is as wide where its points lie as their mean distance from its
  // axis: a cone whose apex lies far beyond the part is a cylinder or a
  // plane there.
  double sum = 0.0;
  for (std::uint32_t i : indices) {
    const Vec3 v = cloud.points[i] - cone->apex;
    sum += (v - v.dot(cone->axisDir) * cone->axisDir).norm();
  }
  return sum <= diag * double(indices.size());
}

Vec3 surfaceNormal(const Surface& surface, const Vec3& p) {
  const Vec3 n = convexNormal(surface, p);
  return surface.convex ? n : Vec3(-n);
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

FitScales fitScales(const DetectionResult& result, const SurfaceFitOptions& options) {
  FitScales scales;
  scales.position = std::max(result.noise, 0.02 * result.epsilon);
  if (!(scales.position > 0.0)) scales.position = 1e-6 * std::max(result.diagonal, 1e-300);
  scales.normal = options.useNormals ? std::max(result.normalNoise, 0.02) : 0.0;
  scales.loss = options.lossScale * result.epsilon;
  if (!(scales.loss > 0.0)) scales.loss = 3.0 * scales.position;
  return scales;
}

// One fit a memo holds: what it was asked (start, points, scales,
// options) and what it gave.
struct FitMemo::Store {
  struct Entry {
    SurfaceShape start;
    std::vector<std::uint32_t> indices;
    FitScales scales;
    std::size_t maxFitPoints = 0;
    int maxIterations = 0;
    double rms = -1.0;  // negative: the fit degenerated, the start stays
    SurfaceShape shape;
    bool convex = true;
  };
  std::mutex mutex;
  std::unordered_map<std::uint64_t, std::vector<Entry>> entries;
  std::size_t hits = 0, solved = 0;
};

FitMemo::FitMemo(const PointCloud& cloud) : cloud_(cloud), store_(std::make_unique<Store>()) {}
FitMemo::~FitMemo() = default;

std::size_t FitMemo::hits() const {
  const std::lock_guard lock(store_->mutex);
  return store_->hits;
}

std::size_t FitMemo::solved() const {
  const std::lock_guard lock(store_->mutex);
  return store_->solved;
}

namespace {

// Bit-for-bit equality of two shapes (the memo's question is "the same
// start?", so -0 and +0 differ too).
bool sameShape(const SurfaceShape& a, const SurfaceShape& b) {
  if (a.index() != b.index()) return false;
  return std::visit(
      [&](const auto& x) {
        using T = std::decay_t<decltype(x)>;
        return std::memcmp(&x, &std::get<T>(b), sizeof(T)) == 0;
      },
      a);
}

bool sameScales(const FitScales& a, const FitScales& b) {
  return a.position == b.position && a.normal == b.normal && a.loss == b.loss;
}

// FNV-1a over the bytes of the start, the points' indices and the scales.
std::uint64_t fitKey(const SurfaceShape& start, std::span<const std::uint32_t> indices,
                     const FitScales& scales) {
  std::uint64_t h = 14695981039346656037ull;
  const auto mix = [&h](const void* data, std::size_t bytes) {
    const auto* c = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) h = (h ^ c[k]) * 1099511628211ull;
  };
  const std::size_t type = start.index();
  mix(&type, sizeof(type));
  std::visit([&](const auto& x) { mix(&x, sizeof(x)); }, start);
  const std::size_t n = indices.size();
  mix(&n, sizeof(n));
  mix(indices.data(), indices.size_bytes());
  mix(&scales.position, sizeof(double));
  mix(&scales.normal, sizeof(double));
  mix(&scales.loss, sizeof(double));
  return h;
}

// The fit itself (fitSurface without its memo).
double solveFit(const PointCloud& cloud, std::span<const std::uint32_t> indices, Surface& surface,
                const FitScales& scales, const SurfaceFitOptions& options);

}  // namespace

double fitSurface(const PointCloud& cloud, std::span<const std::uint32_t> indices, Surface& surface,
                  const FitScales& scales, const SurfaceFitOptions& options, FitMemo* memo) {
  if (!(scales.position > 0.0) || !(scales.loss > 0.0) || !(scales.normal >= 0.0)) {
    throw std::invalid_argument("fitSurface: scales must be positive");
  }
  if (memo == nullptr) return solveFit(cloud, indices, surface, scales, options);
  if (&memo->cloud() != &cloud) {
    throw std::invalid_argument("fitSurface: the memo belongs to another cloud");
  }
  using Entry = FitMemo::Store::Entry;
  FitMemo::Store& store = *memo->store_;
  const std::uint64_t key = fitKey(surface.shape, indices, scales);
  const auto matches = [&](const Entry& e) {
    return e.maxFitPoints == options.maxFitPoints && e.maxIterations == options.maxIterations &&
           sameScales(e.scales, scales) && sameShape(e.start, surface.shape) &&
           std::equal(e.indices.begin(), e.indices.end(), indices.begin(), indices.end());
  };
  {
    const std::lock_guard lock(store.mutex);
    if (const auto it = store.entries.find(key); it != store.entries.end()) {
      for (const Entry& e : it->second) {
        if (!matches(e)) continue;
        ++store.hits;
        if (e.rms >= 0.0) {
          surface.shape = e.shape;
          surface.convex = e.convex;
          surface.rms = e.rms;
        }
        return e.rms;
      }
    }
  }
  Entry entry{surface.shape,
              std::vector<std::uint32_t>(indices.begin(), indices.end()),
              scales,
              options.maxFitPoints,
              options.maxIterations,
              -1.0,
              {},
              true};
  const double rms = solveFit(cloud, indices, surface, scales, options);
  entry.rms = rms;
  if (rms >= 0.0) {
    entry.shape = surface.shape;
    entry.convex = surface.convex;
  }
  const std::lock_guard lock(store.mutex);
  ++store.solved;
  store.entries[key].push_back(std::move(entry));
  return rms;
}

namespace {

double solveFit(const PointCloud& cloud, std::span<const std::uint32_t> indices, Surface& surface,
                const FitScales& scales, const SurfaceFitOptions& options) {
  const std::vector<std::uint32_t> pts =
      evenSubset(indices, std::max<std::size_t>(16, options.maxFitPoints));
  if (pts.size() < 4) return -1.0;
  const PrincipalAxes spread = principalAxes(cloud.points, pts);
  const double extent2 = std::max(spread.covariance.trace(), 1e-300);
  const double guard = 1e-20 * extent2;
  const double minLength = 1e-6 * std::sqrt(extent2);  // radii stay positive
  const bool normals = scales.normal > 0.0 && cloud.hasNormals();
  const auto term = [&](std::uint32_t i) {
    return PointTerm{cloud.points[i],
                     normals ? cloud.normals[i] : Vec3::Zero(),
                     1.0 / scales.position,
                     scales.position,
                     normals ? scales.normal : 0.0,
                     guard};
  };

  SurfaceFit fit(scales, spread.mean, minLength);
  fit.build(surface, pts, term);
  fit.solve(options.maxIterations);
  Surface out = fit.result(surface);
  if (!validSurface(out)) return -1.0;
  orientByNormals(cloud, indices, out);
  const double rms = rmsDistance(cloud, indices, out);
  if (!std::isfinite(rms)) return -1.0;
  out.rms = rms;
  surface = std::move(out);
  return rms;
}

}  // namespace

}  // namespace csgvox
