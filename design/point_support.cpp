#include "design/point_support.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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
  // Each point's leaf is its own (the leaves in order, the first nearest
  // kept): blocks of points on any thread give the same.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      const std::span<const Vec3> block = points.subspan(r.begin(), r.size());
                      std::vector<double> best(r.size(), band), v(r.size());
                      for (const Node* leaf : ordered) {
                        leaf->primitive.values(block, v);
                        for (std::size_t j = 0; j < r.size(); ++j) {
                          const std::size_t i = r.begin() + j;
                          if (std::abs(f[i]) > band || !(std::abs(v[j]) < best[j])) continue;
                          best[j] = std::abs(v[j]);
                          s.leaf[i] = leaf;
                        }
                      }
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        if (s.leaf[i])
                          s.leaf[i]->primitive.valueAndGradient(points[i], s.gradient[i]);
                      }
                    });
  return s;
}

}  // namespace csgvox
