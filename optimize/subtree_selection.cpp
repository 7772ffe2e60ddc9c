#include "optimize/subtree_selection.h"

#include <algorithm>
#include <cassert>

#include "optimize/branch_and_bound.h"
#include "optimize/distinct_items.h"
#include "optimize/selection_classes.h"

namespace csgvox {
namespace {

// Eq. 4 on the root's own voxels (the universe): the items are the voxels
// each action removes, channel 0 the inside voxels, channel 1 the outside
// ones; the truncated root keeps what no chosen action removes.
class TruncationObjective final : public SelectionObjective {
 public:
  TruncationObjective(std::size_t insideCount, std::size_t outsideCount, double invL, double alpha)
      : insideCount_(insideCount), outsideCount_(outsideCount), invL_(invL), alpha_(alpha) {}

  double energy(std::size_t chosen, const ChannelCounts& removed) const override {
    return fit(chosen, removed[0], removed[1]);
  }
  // The inside kept can only shrink, the outside kept can shrink at most to
  // what the remaining actions cannot remove; each further action costs 1/L.
  double bound(std::size_t chosen, const ChannelCounts& removed,
               std::size_t outsideReach) const override {
    return fit(chosen, removed[0], outsideReach);
  }

 private:
  double fit(std::size_t chosen, std::size_t removedIn, std::size_t removedOut) const {
    const double num = double(insideCount_ - removedIn);
    const double den = double(insideCount_ + outsideCount_ - removedOut);
    return double(chosen) * invL_ - alpha_ * (den > 0.0 ? num / den : 0.0);
  }

  std::size_t insideCount_, outsideCount_;
  double invL_, alpha_;
};

// The local search's stream for a run seed.
constexpr std::uint64_t kRestartStream = 12345;

}  // namespace

double subtreeEnergy(const VoxelSet& root, const VoxelSet& inside,
                     const std::vector<const VoxelSet*>& neighbours,
                     const std::vector<std::uint8_t>& chosen, double alpha) {
  VoxelSet sub = root;
  std::size_t count = 0;
  for (std::size_t i = 0; i < neighbours.size(); ++i) {
    if (chosen[2 * i]) sub &= *neighbours[i], ++count;
    if (chosen[2 * i + 1]) sub.subtract(*neighbours[i]), ++count;
  }
  const double plusRoot = double(VoxelSet::countAnd(root, inside));
  const double num = double(VoxelSet::countAnd(sub, inside));
  const double den = plusRoot + double(VoxelSet::countAndNot(sub, inside));
  const double L = double(2 * neighbours.size());
  return (L > 0 ? double(count) / L : 0.0) - alpha * (den > 0 ? num / den : 0.0);
}

SubtreeResult selectSubtree(const VoxelSet& root, const VoxelSet& inside,
                            const std::vector<const VoxelSet*>& neighbours,
                            const std::vector<std::uint32_t>& neighbourIds,
                            const SubtreeOptions& options) {
  assert(neighbours.size() == neighbourIds.size());
  SubtreeResult result;
  result.actionCount = 2 * neighbours.size();
  // Work on the root's own voxels only, in the grid's order: an action's
  // item is the part of the root it removes, given by its neighbour
  // (GeneratedItem), never built.
  const VoxelSet rootInside = root & inside;
  const VoxelSet rootOutside = root - inside;
  const std::size_t rootCount = root.count();
  const std::size_t insideCount = rootInside.count();
  const std::size_t outsideCount = rootCount - insideCount;
  double invL = 0.0;
  if (options.minFeatureVoxels > 0.0) {
    invL = options.minFeatureVoxels / double(std::max<std::size_t>(1, insideCount));
  } else {
    invL = result.actionCount ? 1.0 / double(result.actionCount) : 0.0;
  }
  // Useful actions: those removing at least one outside voxel; an action that
  // removes only inside voxels never belongs to an optimum. Actions with the
  // same effect are kept once. An item's id is 2i (+1 for subtract).
  struct Action {
    std::uint32_t id;
    GeneratedItem item;
    double score;
  };
  std::vector<Action> actions;
  DistinctItems distinct(root);
  for (std::size_t i = 0; i < neighbours.size() && outsideCount > 0; ++i) {
    const std::size_t inRoot = VoxelSet::countAnd(*neighbours[i], root);
    const std::size_t inRootInside = VoxelSet::countAnd(*neighbours[i], rootInside);
    for (int sub = 0; sub < 2; ++sub) {
      // Intersecting removes the root's voxels outside the neighbour,
      // subtracting those inside it.
      const std::size_t removedCount = sub ? inRoot : rootCount - inRoot;
      const std::size_t removesOut =
          sub ? inRoot - inRootInside : outsideCount - (inRoot - inRootInside);
      if (removesOut == 0) continue;
      // An action removing k outside voxels improves the fit term by at most
      // alpha * k / |V+(root)| in any solution (the denominator never drops
      // below |V+(root)|, the numerator never exceeds it) and costs
      // minFeatureVoxels / |V+(root)|: when alpha * k <= minFeatureVoxels it
      // never pays for itself, so no optimum holds it. Exact, and on noisy
      // labels it drops most actions.
      if (options.minFeatureVoxels > 0.0 &&
          options.alpha * double(removesOut) <= options.minFeatureVoxels) {
        continue;
      }
      // Order: most outside removed per inside lost first (good incumbents early).
      const double out = double(removesOut);
      if (distinct.add(*neighbours[i], sub == 0, removedCount)) {
        actions.push_back({std::uint32_t(2 * i + std::size_t(sub)),
                           GeneratedItem{std::uint32_t(i), sub == 0},
                           out / (1.0 + double(removedCount) - out)});
      }
    }
  }
  result.usefulActions = actions.size();
  std::stable_sort(actions.begin(), actions.end(),
                   [](const Action& a, const Action& b) { return a.score > b.score; });
  std::vector<GeneratedItem> items;
  for (const Action& a : actions) items.push_back(a.item);
  const std::vector<const VoxelSet*> channels{&rootInside, &rootOutside};
  const SelectionClasses classes(neighbours, items, root, channels);

  const Selection best = solveSelection(
      classes, 1, TruncationObjective(insideCount, outsideCount, invL, options.alpha),
      phaseSearch(options, 3, kRestartStream));
  result.provedOptimal = best.provedOptimal;
  result.energy = best.energy;
  result.voxels = root;
  for (std::size_t a = 0; a < best.chosen.size(); ++a) {
    if (!best.chosen[a]) continue;
    const std::size_t idx = actions[a].id;
    SubtreeAction act{neighbourIds[idx / 2], idx % 2 == 1};
    result.actions.push_back(act);
    if (act.subtract) {
      result.voxels.subtract(*neighbours[idx / 2]);
    } else {
      result.voxels &= *neighbours[idx / 2];
    }
  }
  return result;
}

}  // namespace csgvox
