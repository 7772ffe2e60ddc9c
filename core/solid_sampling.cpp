#include "core/solid_sampling.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/seed.h"

namespace csgvox {
namespace {

// The points of layer k (cells[2] layers along z) of the stratified grid,
// from a generator of the layer's own, so layers can be made one at a time.
void layerPoints(const Aabb& box, const std::array<int, 3>& cells, int k, std::uint64_t seed,
                 std::vector<Vec3>& out) {
  std::mt19937_64 rng(mixSeed(seed, std::uint64_t(k)));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 cell = box.size().cwiseQuotient(Vec3(cells[0], cells[1], cells[2]));
  out.clear();
  for (int j = 0; j < cells[1]; ++j) {
    for (int i = 0; i < cells[0]; ++i) {
      const double x = i + u(rng), y = j + u(rng), z = k + u(rng);
      out.push_back(box.min + Vec3(x * cell.x(), y * cell.y(), z * cell.z()));
    }
  }
}

void checkBox(const Aabb& box) {
  if (box.isEmpty() || !box.isBounded()) {
    throw std::invalid_argument("solid sampling needs a bounded, non-empty box");
  }
}

}  // namespace

std::vector<Vec3> stratifiedPoints(const Aabb& box, const std::array<int, 3>& cells,
                                   std::uint64_t seed) {
  checkBox(box);
  std::vector<Vec3> out, layer;
  out.reserve(std::size_t(cells[0]) * cells[1] * cells[2]);
  for (int k = 0; k < cells[2]; ++k) {
    layerPoints(box, cells, k, seed, layer);
    out.insert(out.end(), layer.begin(), layer.end());
  }
  return out;
}

std::vector<Vec3> stratifiedPoints(const Aabb& box, int n, std::uint64_t seed) {
  return stratifiedPoints(box, {n, n, n}, seed);
}

double sampledVolume(const CsgTree& tree, const Aabb& box, int n, std::uint64_t seed) {
  if (n < 1) throw std::invalid_argument("sampledVolume: n < 1");
  checkBox(box);
  const std::array<int, 3> cells = {n, n, n};
  std::vector<Vec3> points;
  std::vector<double> f;
  std::size_t inside = 0;
  for (int k = 0; k < n; ++k) {
    layerPoints(box, cells, k, seed, points);
    f.resize(points.size());
    tree.values(points, f);
    inside += std::size_t(std::count_if(f.begin(), f.end(), [](double v) { return v >= 0.0; }));
  }
  return double(inside) / (double(n) * n * n) * box.size().prod();
}

double volumetricIou(const CsgTree& a, const CsgTree& b, int resolution, std::uint64_t seed) {
  if (a.empty() || b.empty()) throw std::invalid_argument("volumetricIou: an empty tree");
  if (resolution < 2) throw std::invalid_argument("volumetricIou: resolution < 2");
  Aabb box = a.bounds();
  box.extend(b.bounds());
  if (box.isEmpty()) return 1.0;
  if (!box.isBounded()) throw std::invalid_argument("volumetricIou: an unbounded solid");
  const double step = box.size().maxCoeff() / resolution;
  std::array<int, 3> cells;
  for (int k = 0; k < 3; ++k) cells[k] = std::max(1, int(std::ceil(box.size()[k] / step)));
  std::vector<Vec3> points;
  std::vector<double> fa, fb;
  std::size_t both = 0, either = 0;
  for (int k = 0; k < cells[2]; ++k) {
    layerPoints(box, cells, k, seed, points);
    fa.resize(points.size());
    fb.resize(points.size());
    a.values(points, fa);
    b.values(points, fb);
    for (std::size_t i = 0; i < points.size(); ++i) {
      both += fa[i] >= 0.0 && fb[i] >= 0.0;
      either += fa[i] >= 0.0 || fb[i] >= 0.0;
    }
  }
  return either ? double(both) / double(either) : 1.0;
}

}  // namespace csgvox
