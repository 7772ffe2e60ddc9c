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
  // side of at least a millionth of D), then the point's random rank.
  struct Entry {
    std::uint64_t cell;
    std::uint64_t rank;
    std::uint32_t index;
  };
  std::vector<Entry> entries(n);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const Vec3 c = ((points[i] - lo) / side).array().floor();
    const auto axis = [](double v) {
      return std::uint64_t(std::clamp(v, 0.0, double((1u << 21) - 1)));
    };
    entries[i] = {axis(c.x()) << 42 | axis(c.y()) << 21 | axis(c.z()),
                  mixSeed(options.seed, std::uint64_t(i)), std::uint32_t(i)};
  });
  // The rank breaks no ties between equal keys: the index does, so the
  // order (and the choice) is the same whatever the sort's schedule.
  tbb::parallel_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.cell != b.cell ? a.cell < b.cell
                            : (a.rank != b.rank ? a.rank < b.rank : a.index < b.index);
  });
  std::vector<std::size_t> start;  // first entry of each cell, then n
  for (std::size_t k = 0; k < n; ++k) {
    if (k == 0 || entries[k].cell != entries[k - 1].cell) start.push_back(k);
  }
  start.push_back(n);
  std::vector<std::size_t> counts(start.size() - 1);
  for (std::size_t c = 0; c + 1 < start.size(); ++c) counts[c] = start[c + 1] - start[c];
  // The largest q with sum(min(count, q)) <= points (at least 1).
  std::vector<std::size_t> sorted = counts;
  std::sort(sorted.begin(), sorted.end());
  std::size_t q = 1, below = 0;  // below: sum of the counts under the candidate q
  for (std::size_t c = 0; c < sorted.size(); ++c) {
    // For q in (sorted[c-1], sorted[c]]: kept = below + q * (cells from c on).
    const std::size_t rest = sorted.size() - c;
    const std::size_t room = options.points > below ? options.points - below : 0;
    const std::size_t best = room / rest;
    if (best < sorted[c]) {
      q = std::max<std::size_t>(q, best);
      break;
    }
    q = sorted[c];
    below += sorted[c];
  }
  std::vector<std::uint32_t> kept;
  kept.reserve(std::min(n, q * counts.size()));
  for (std::size_t c = 0; c + 1 < start.size(); ++c) {
    const std::size_t end = std::min(start[c + 1], start[c] + q);
    for (std::size_t k = start[c]; k < end; ++k) kept.push_back(entries[k].index);
  }
  tbb::parallel_sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace csgvox
