#include "design/pattern_detection.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/export_extent.h"

namespace csgvox {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// The primitive moved to the origin with its axis's sign fixed, so that
// equal shapes compare equal.
Primitive shapeKey(const Primitive& p, bool loose) {
  const auto positive = [](const Vec3& a) {
    for (int i = 0; i < 3; ++i) {
      if (std::abs(a[i]) > 1e-9) return a[i] > 0.0;
    }
    return true;
  };
  return std::visit(
      [&](auto s) -> Primitive {
        using T = decltype(s);
        if constexpr (std::is_same_v<T, HalfSpace>) {
          return s;
        } else if constexpr (std::is_same_v<T, Box>) {
          s = canonicalBox(s);
          s.center = Vec3::Zero();
        } else if constexpr (std::is_same_v<T, Sphere>) {
          s.center = Vec3::Zero();
        } else if constexpr (std::is_same_v<T, Cone>) {
          s.center = Vec3::Zero();
          if (!positive(s.axis)) {
            s.axis = -s.axis;
            std::swap(s.radiusBottom, s.radiusTop);
          }
        } else {
          s.center = Vec3::Zero();
          if (!positive(s.axis)) s.axis = -s.axis;
          if constexpr (std::is_same_v<T, Cylinder>) {
            if (loose) s.height = 1.0;
          }
        }
        return s;
      },
      p.shape());
}

bool alongZ(const Primitive& p, double tol) {
  Vec3 axis;
  if (const auto* c = p.as<Cylinder>())
    axis = c->axis;
  else if (const auto* c = p.as<Cone>())
    axis = c->axis;
  else if (const auto* t = p.as<Torus>())
    axis = t->axis;
  else
    return p.type() == PrimitiveType::Sphere;
  return std::abs(axis.x()) <= tol && std::abs(axis.y()) <= tol;
}

bool circular(const std::vector<int>& group, std::span<const PatternCandidate> prims,
              const std::vector<Vec3>& pos, double tol, FoundPattern& out) {
  const int n = int(group.size());
  if (n < 3) return false;
  Vec3 m = Vec3::Zero();
  for (int i : group) {
    if (!alongZ(prims[std::size_t(i)].primitive, tol / 100)) return false;
    m += pos[std::size_t(i)];
  }
  m /= n;
  std::vector<std::pair<double, int>> angles;
  double radius = 0.0;
  for (int i : group) {
    const Vec3 d = pos[std::size_t(i)] - m;
    if (std::abs(d.z()) > tol) return false;
    radius += std::hypot(d.x(), d.y()) / n;
    double a = std::atan2(d.y(), d.x()) * kDeg;
    if (a < 0) a += 360.0;
    angles.emplace_back(a, i);
  }
  if (radius <= tol) return false;
  const double angleTol = tol / radius * kDeg;
  const double step = 360.0 / n;
  std::sort(angles.begin(), angles.end());
  for (int k = 0; k < n; ++k) {
    const Vec3 d = pos[std::size_t(angles[k].second)] - m;
    if (std::abs(std::hypot(d.x(), d.y()) - radius) > tol) return false;
    if (std::abs(angles[k].first - angles[0].first - k * step) > angleTol) return false;
  }
  out.kind = FoundPatternKind::Circular;
  out.center = m;
  out.radius = radius;
  // Member 0: the first at or after angle 0 (angles mod the step).
  double phase = 0.0;
  for (int k = 0; k < n; ++k) phase += (angles[k].first - k * step) / n;
  phase = std::fmod(phase + 360.0, step);
  if (step - phase <= angleTol) phase -= step;
  out.phase = phase;
  // Order from the member nearest the phase.
  int first = 0;
  for (int k = 0; k < n; ++k) {
    const double off = std::remainder(angles[k].first - phase, 360.0);
    if (std::abs(off) < std::abs(std::remainder(angles[first].first - phase, 360.0))) first = k;
  }
  out.members.clear();
  for (int k = 0; k < n; ++k) out.members.push_back(angles[std::size_t((first + k) % n)].second);
  out.count = n;
  return true;
}

// Sorted distinct values (clusters within tol, their means).
std::vector<double> levels(std::vector<double> v, double tol) {
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  std::vector<int> counts;
  for (double x : v) {
    if (!out.empty() && x - out.back() / counts.back() <= tol) {
      out.back() += x;
      ++counts.back();
    } else {
      out.push_back(x);
      counts.push_back(1);
    }
  }
  for (std::size_t i = 0; i < out.size(); ++i) out[i] /= counts[i];
  return out;
}

bool evenlySpaced(const std::vector<double>& v, double tol) {
  if (v.size() < 2) return true;
  const double step = (v.back() - v.front()) / double(v.size() - 1);
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (std::abs(v[i] - v.front() - double(i) * step) > tol) return false;
  }
  return true;
}

bool lattice(const std::vector<int>& group, std::span<const PatternCandidate>,
             const std::vector<Vec3>& pos, double tol, FoundPattern& out) {
  const int n = int(group.size());
  if (n < 4) return false;
  std::array<std::vector<double>, 3> lv;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> v;
    for (int i : group) v.push_back(pos[std::size_t(i)][a]);
    lv[a] = levels(v, tol);
    if (!evenlySpaced(lv[a], tol)) return false;
  }
  std::vector<int> axes;
  for (int a = 0; a < 3; ++a) {
    if (lv[a].size() > 1) axes.push_back(a);
  }
  if (axes.size() != 2 || int(lv[axes[0]].size() * lv[axes[1]].size()) != n) return false;
  const int a = axes[0], b = axes[1];
  const int na = int(lv[a].size()), nb = int(lv[b].size());
  std::vector<int> members(std::size_t(n), -1);
  for (int i : group) {
    const Vec3 c = pos[std::size_t(i)];
    int ia = -1, ib = -1;
    for (int k = 0; k < na; ++k)
      if (std::abs(c[a] - lv[a][k]) <= tol) ia = k;
    for (int k = 0; k < nb; ++k)
      if (std::abs(c[b] - lv[b][k]) <= tol) ib = k;
    if (ia < 0 || ib < 0 || members[std::size_t(ia + na * ib)] >= 0) return false;
    members[std::size_t(ia + na * ib)] = i;
  }
  out.kind = FoundPatternKind::Lattice;
  out.members = members;
  out.count = na;
  out.count2 = nb;
  out.step = Vec3::Zero();
  out.step2 = Vec3::Zero();
  out.step[a] = (lv[a].back() - lv[a].front()) / (na - 1);
  out.step2[b] = (lv[b].back() - lv[b].front()) / (nb - 1);
  return true;
}

bool row(const std::vector<int>& group, std::span<const PatternCandidate>,
         const std::vector<Vec3>& pos, double tol, FoundPattern& out) {
  const int n = int(group.size());
  if (n < 2) return false;
  // Along the line through the two farthest members, in order.
  int p = 0, q = 1;
  double far = -1.0;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const double d =
          (pos[std::size_t(group[std::size_t(j)])] - pos[std::size_t(group[std::size_t(i)])])
              .norm();
      if (d > far + tol) {
        far = d;
        p = i;
        q = j;
      }
    }
  if (far <= tol) return false;
  const Vec3 c0 = pos[std::size_t(group[std::size_t(p)])];
  Vec3 dir = pos[std::size_t(group[std::size_t(q)])] - c0;
  // Point the row so that it runs up the frame's axes (deterministic).
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) > tol) {
      if (dir[a] < 0) dir = -dir;
      break;
    }
  }
  std::vector<std::pair<double, int>> order;
  for (int i : group) order.emplace_back(pos[std::size_t(i)].dot(dir), i);
  std::sort(order.begin(), order.end());
  const Vec3 first = pos[std::size_t(order.front().second)];
  const Vec3 step = (pos[std::size_t(order.back().second)] - first) / (n - 1);
  out.members.clear();
  for (int k = 0; k < n; ++k) {
    const Vec3 c = pos[std::size_t(order[std::size_t(k)].second)];
    if ((c - first - k * step).norm() > tol) return false;
    out.members.push_back(order[std::size_t(k)].second);
  }
  out.kind = FoundPatternKind::Row;
  out.step = step;
  out.count = n;
  return true;
}

}  // namespace

Vec3 primitiveCenter(const Primitive& p) {
  return std::visit(
      [](const auto& s) -> Vec3 {
        if constexpr (requires { s.center; }) {
          return s.center;
        } else {
          return Vec3::Zero();
        }
      },
      p.shape());
}

std::vector<FoundPattern> findPatterns(std::span<const PatternCandidate> primitives,
                                       const PatternOptions& options) {
  const double tol = options.tolerance;
  // Positions compared: the centres, less the axial part of a loose cylinder's
  // (its caps are free) when every loose one shares the direction.
  std::vector<Vec3> pos;
  for (const PatternCandidate& c : primitives) {
    Vec3 p = primitiveCenter(c.primitive);
    if (const auto* cyl = c.primitive.as<Cylinder>(); cyl && c.looseLength) {
      p -= p.dot(cyl->axis) * cyl->axis;
    }
    pos.push_back(p);
  }
  // Groups of equal shapes, in input order.
  std::vector<Primitive> keys;
  std::vector<std::vector<int>> groups;
  for (std::size_t i = 0; i < primitives.size(); ++i) {
    if (!primitives[i].primitive.isBounded()) continue;
    const Primitive key = shapeKey(primitives[i].primitive, primitives[i].looseLength);
    std::size_t g = 0;
    while (g < keys.size() && !keys[g].approxEqual(key, tol)) ++g;
    if (g == keys.size()) {
      keys.push_back(key);
      groups.emplace_back();
    }
    groups[g].push_back(int(i));
  }
  std::vector<FoundPattern> found;
  for (const auto& group : groups) {
    if (group.size() < 2) continue;
    FoundPattern p;
    // Loose and firm lengths do not mix in one pattern.
    bool mixed = false;
    for (int i : group)
      mixed = mixed || primitives[std::size_t(i)].looseLength !=
                           primitives[std::size_t(group.front())].looseLength;
    if (mixed) continue;
    if (circular(group, primitives, pos, tol, p) || lattice(group, primitives, pos, tol, p) ||
        row(group, primitives, pos, tol, p)) {
      found.push_back(p);
    }
  }
  return found;
}

}  // namespace csgvox
