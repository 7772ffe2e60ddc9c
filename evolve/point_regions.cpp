#include "evolve/point_regions.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include "core/union_find.h"

namespace csgvox {
namespace {

using Cell = std::array<std::int64_t, 3>;

struct CellHash {
  std::size_t operator()(const Cell& c) const {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (const std::int64_t v : c) h = (h ^ std::uint64_t(v)) * 0x100000001b3ull;
    return std::size_t(h);
  }
};

}  // namespace

std::vector<std::vector<std::uint32_t>> pointRegions(std::span<const Vec3> points,
                                                     std::span<const std::uint32_t> subset,
                                                     double cell) {
  if (!(cell > 0.0)) throw std::invalid_argument("region cells need a size > 0");
  // Occupied cells, numbered in order of first appearance.
  std::unordered_map<Cell, std::size_t, CellHash> cells;
  std::vector<Cell> cellOf;
  std::vector<std::size_t> pointCell(subset.size());
  for (std::size_t k = 0; k < subset.size(); ++k) {
    if (subset[k] >= points.size()) throw std::invalid_argument("region point index out of range");
    const Vec3& p = points[subset[k]];
    const Cell c = {std::int64_t(std::floor(p.x() / cell)), std::int64_t(std::floor(p.y() / cell)),
                    std::int64_t(std::floor(p.z() / cell))};
    const auto [it, added] = cells.emplace(c, cellOf.size());
    if (added) cellOf.push_back(c);
    pointCell[k] = it->second;
  }
  std::vector<std::size_t> parent(cellOf.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  for (std::size_t i = 0; i < cellOf.size(); ++i) {
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const Cell n = {cellOf[i][0] + dx, cellOf[i][1] + dy, cellOf[i][2] + dz};
          const auto it = cells.find(n);
          if (it == cells.end()) continue;
          const std::size_t a = findRoot(parent, i), b = findRoot(parent, it->second);
          if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
      }
    }
  }
  // Regions in order of their smallest point index.
  std::vector<std::size_t> order(subset.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return subset[a] < subset[b]; });
  std::unordered_map<std::size_t, std::size_t> regionOf;
  std::vector<std::vector<std::uint32_t>> out;
  for (const std::size_t k : order) {
    const std::size_t root = findRoot(parent, pointCell[k]);
    const auto [it, added] = regionOf.emplace(root, out.size());
    if (added) out.emplace_back();
    out[it->second].push_back(subset[k]);
  }
  return out;
}

}  // namespace csgvox
