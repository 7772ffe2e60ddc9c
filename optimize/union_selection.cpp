#include "optimize/union_selection.h"

#include <algorithm>
#include <limits>

#include "optimize/branch_and_bound.h"
#include "optimize/distinct_items.h"
#include "optimize/selection_classes.h"

namespace csgvox {
namespace {

// Eq. 6 on the inside voxels (the universe, the one channel): the items are
// the voxels each candidate covers.
class CoverageObjective final : public SelectionObjective {
 public:
  CoverageObjective(double invM, double beta, double invTotal)
      : invM_(invM), beta_(beta), invTotal_(invTotal) {}

  double energy(std::size_t chosen, const ChannelCounts& covered) const override {
    return fit(chosen, covered[0]);
  }
  // Everything the remaining candidates could add, for at least one more
  // candidate; nothing when they add nothing.
  double bound(std::size_t chosen, const ChannelCounts& covered, std::size_t reach) const override {
    if (reach == covered[0]) return std::numeric_limits<double>::infinity();
    return fit(chosen + 1, reach);
  }

 private:
  double fit(std::size_t chosen, std::size_t covered) const {
    return double(chosen) * invM_ - beta_ * double(covered) * invTotal_;
  }

  double invM_, beta_, invTotal_;
};

// The local search's stream for a run seed.
constexpr std::uint64_t kRestartStream = 54321;

}  // namespace

double unionEnergy(const VoxelSet& inside, const std::vector<const VoxelSet*>& candidates,
                   const std::vector<std::uint8_t>& chosen, double beta) {
  VoxelSet all(inside.size());
  std::size_t count = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (chosen[i]) all |= *candidates[i], ++count;
  }
  const double total = double(inside.count());
  const double m = double(candidates.size());
  return (m > 0 ? double(count) / m : 0.0) -
         beta * (total > 0 ? double(VoxelSet::countAnd(inside, all)) / total : 0.0);
}

UnionResult selectUnion(const VoxelSet& inside, const std::vector<const VoxelSet*>& candidates,
                        const UnionOptions& options) {
  UnionResult result;
  const std::size_t total = inside.count();
  double invM = 0.0;
  if (options.minFeatureVoxels > 0.0) {
    invM = options.minFeatureVoxels / double(std::max<std::size_t>(1, total));
  } else {
    invM = candidates.empty() ? 0.0 : 1.0 / double(candidates.size());
  }
  const double invTotal = total ? 1.0 / double(total) : 0.0;
  // Work on the inside voxels only, in the grid's order: a candidate's item
  // is the inside voxels it covers, given by the candidate (GeneratedItem),
  // never built. Candidates covering nothing, or exactly what an earlier one
  // covers, never improve an optimum.
  struct Item {
    std::uint32_t candidate;
    double size;
  };
  std::vector<Item> order;
  DistinctItems distinct(inside);
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const std::size_t size = VoxelSet::countAnd(*candidates[i], inside);
    if (size == 0) continue;
    if (distinct.add(*candidates[i], false, size))
      order.push_back({std::uint32_t(i), double(size)});
  }
  // Largest first: good incumbents early, strong suffix bounds.
  std::stable_sort(order.begin(), order.end(),
                   [](const Item& a, const Item& b) { return a.size > b.size; });
  std::vector<GeneratedItem> items;
  for (const Item& item : order) items.push_back({item.candidate, false});
  const std::vector<const VoxelSet*> channels{&inside};
  const SelectionClasses classes(candidates, items, inside, channels);
  const Selection best = solveSelection(classes, 0, CoverageObjective(invM, options.beta, invTotal),
                                        phaseSearch(options, 8, kRestartStream));
  result.provedOptimal = best.provedOptimal;
  result.energy = best.energy;
  VoxelSet covered(inside.size());
  for (std::size_t i = 0; i < best.chosen.size(); ++i) {
    if (best.chosen[i]) {
      result.chosen.push_back(order[i].candidate);
      covered |= *candidates[order[i].candidate];
    }
  }
  std::sort(result.chosen.begin(), result.chosen.end());
  result.covered = VoxelSet::countAnd(covered, inside);
  return result;
}

}  // namespace csgvox
