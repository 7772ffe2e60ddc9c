#include "primitives/even_subsample.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/seed.h"

namespace csgvox {

std::vector<std::uint32_t> evenSubsample(std::span<const Vec3> points, double noise,
                                         const SubsampleOptions& options) {
  if (options.points == 0 || !(options.cellSide > 0.0) || !(options.noiseCells >= 0.0) ||
      !(noise >= 0.0)) {
    throw std::invalid_argument("evenSubsample: an option is out of range");
  }
  const std::size_t n = points.size();
  std::vector<std::uint32_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = std::uint32_t(i);
  if (n <= options.points) return all;

  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double diag = (hi - lo).norm();
  const double side = std::max(options.cellSide * diag, options.noiseCells * noise);
  if (!(side > 0.0)) return all;
  // Cell keys in 21 bits per axis (2 million cells along a side: ample for a
  // side of at least a millionth of D).
  std::vector<std::uint64_t> key(n);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const Vec3 c = ((points[i] - lo) / side).array().floor();
    const auto axis = [](double v) {
      return std::uint64_t(std::clamp(v, 1.0, double((1u << 21) - 2)));
    };
    key[i] = axis(c.x() + 1.0) << 42 | axis(c.y() + 1.0) << 21 | axis(c.z() + 1.0);
  });
  std::vector<std::uint64_t> cells = key;
  tbb::parallel_sort(cells.begin(), cells.end());
  std::vector<std::size_t> count;
  std::size_t unique = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0 && cells[k] == cells[unique - 1]) {
      ++count.back();
    } else {
      cells[unique++] = cells[k];
      count.push_back(1);
    }
  }
  cells.resize(unique);
  const auto cellOf = [&](std::uint64_t k) {
    const auto it = std::lower_bound(cells.begin(), cells.end(), k);
    return it != cells.end() && *it == k ? std::ptrdiff_t(it - cells.begin()) : std::ptrdiff_t(-1);
  };
  // A cell's density is the largest count among it and the 26 cells around
  // it: a cell that holds only the tail of a noise band (cut by a cell
  // face) is thinned as much as the band's middle, so the noise keeps its
  // distribution.
  std::vector<double> density(unique);
  tbb::parallel_for(std::size_t(0), unique, [&](std::size_t c) {
    std::size_t most = 0;
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const std::uint64_t k = std::uint64_t(std::int64_t(cells[c]) + (dx << 42) +
                                                (dy << 21) + dz);
          if (const std::ptrdiff_t o = cellOf(k); o >= 0) most = std::max(most, count[std::size_t(o)]);
        }
      }
    }
    density[c] = double(most);
  });
  // Each point of cell c is kept with probability min(1, q / density[c]);
  // q (by bisection) makes the expected count options.points.
  const auto expected = [&](double q) {
    double sum = 0.0;
    for (std::size_t c = 0; c < unique; ++c) sum += double(count[c]) * std::min(1.0, q / density[c]);
    return sum;
  };
  double qLo = 0.0, qHi = double(n);
  for (int it = 0; it < 60; ++it) {
    const double q = 0.5 * (qLo + qHi);
    (expected(q) <= double(options.points) ? qLo : qHi) = q;
  }
  std::vector<char> keep(n, 0);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const double p = std::min(1.0, qLo / density[std::size_t(cellOf(key[i]))]);
    const double u = double(mixSeed(options.seed, std::uint64_t(i)) >> 11) * 0x1.0p-53;
    keep[i] = u < p;
  });
  std::vector<std::uint32_t> kept;
  kept.reserve(options.points + options.points / 8);
  for (std::size_t i = 0; i < n; ++i) {
      if (keep[i]) kept.push_back(std::uint32_t(i));
  }
  return kept;
}

}  // namespace csgvox
