#include "design/point_support.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace csgvox {

PointSupport pointSupport(const CsgTree& tree, std::span<const Vec3> points,
                          const SupportOptions& options) {
  if (tree.empty()) throw std::invalid_argument("pointSupport: empty tree");
  PointSupport s;
  if (points.empty()) return s;
  Aabb box;
  for (const Vec3& p : points) box.extend(p);
  std::vector<double> f(points.size());
  tree.values(points, f);
  std::vector<double> absF(f.size());
  std::transform(f.begin(), f.end(), absF.begin(), [](double v) { return std::abs(v); });
  const auto mid = absF.begin() + std::ptrdiff_t(absF.size() / 2);
  std::nth_element(absF.begin(), mid, absF.end());
  s.noise = std::max(1.4826 * *mid, options.noiseFloor * box.diagonal());
  const double band = std::max(options.band * s.noise, options.leastBand);

  // Each leaf once, in the tree's order (deterministic ties).
  const std::vector<const Node*> ordered = tree.distinctLeaves();
  s.leaf.assign(points.size(), nullptr);
  s.gradient.assign(points.size(), Vec3::Zero());
  std::vector<double> best(points.size(), band);
  std::vector<double> v(points.size());
  for (const Node* leaf : ordered) {
    leaf->primitive.values(points, v);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (std::abs(f[i]) > band || !(std::abs(v[i]) < best[i])) continue;
      best[i] = std::abs(v[i]);
      s.leaf[i] = leaf;
    }
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (s.leaf[i]) s.leaf[i]->primitive.valueAndGradient(points[i], s.gradient[i]);
  }
  return s;
}

}  // namespace csgvox
