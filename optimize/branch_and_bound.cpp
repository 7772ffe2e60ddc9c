#include "optimize/branch_and_bound.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <limits>
#include <numeric>
#include <random>

#include "optimize/cover_state.h"

namespace csgvox {
namespace {

// Depth-first over the items in order: at item t, include it (when it adds
// voxels of the bound channel) or not. A node is cut when the objective's
// bound, over everything the remaining items could add, cannot beat the best
// energy found.
class BranchAndBound {
 public:
  BranchAndBound(const SelectionProblem& pb, const SelectionObjective& objective,
                 const SelectionOptions& options)
      : pb_(pb), objective_(objective), budget_(options.nodeBudget), deadline_(options.deadline) {
    const auto& items = pb.items();
    const std::size_t n = items.size();
    suffix_.assign(n + 1, VoxelSet(pb.universe()));
    for (std::size_t t = n; t-- > 0;) {
      suffix_[t] = suffix_[t + 1] | items[t].parts[pb.boundChannel()];
    }
  }

  // Returns true when the search finished within the budget.
  bool run(std::vector<std::uint8_t>& best, double& bestEnergy) {
    best_ = best;
    bestEnergy_ = bestEnergy;
    std::vector<std::uint8_t> current(pb_.items().size(), 0);
    search(0, 0, VoxelSet(pb_.universe()), current);
    best = best_;
    bestEnergy = bestEnergy_;
    return nodes_ <= budget_;
  }

 private:
  void search(std::size_t t, std::size_t chosen, const VoxelSet& united,
              std::vector<std::uint8_t>& current) {
    if (++nodes_ > budget_) return;
    // The clock is read every 1024 nodes; past the deadline the search ends
    // as if the budget were spent.
    if ((nodes_ & 1023) == 0 && std::chrono::steady_clock::now() > deadline_) {
      budget_ = nodes_ - 1;
      return;
    }
    const ChannelCounts counts = pb_.counts(united);
    const double e = objective_.energy(chosen, counts);
    if (e < bestEnergy_ - 1e-12) {
      bestEnergy_ = e;
      best_ = current;
    }
    const auto& items = pb_.items();
    if (t == items.size()) return;
    if (objective_.bound(chosen, counts, reach(united, suffix_[t])) >= bestEnergy_ - 1e-12) return;
    if (addsToBoundChannel(items[t], united)) {
      current[t] = 1;
      search(t + 1, chosen + 1, united | items[t].set, current);
      current[t] = 0;
    }
    search(t + 1, chosen, united, current);
  }

  // |(united ∩ bound channel) ∪ suffix|: the most of the bound channel any
  // completion can hold.
  std::size_t reach(const VoxelSet& united, const VoxelSet& suffix) const {
    const auto u = united.words(), c = pb_.channel(pb_.boundChannel()).words(), s = suffix.words();
    std::size_t n = 0;
    for (std::size_t w = 0; w < u.size(); ++w)
      n += std::size_t(std::popcount((u[w] & c[w]) | s[w]));
    return n;
  }

  // True when the item adds a voxel of the bound channel to `united`.
  bool addsToBoundChannel(const SelectionItem& item, const VoxelSet& united) const {
    const auto a = item.parts[pb_.boundChannel()].words(), u = united.words();
    return std::any_of(item.words.begin(), item.words.end(),
                       [&](std::uint32_t w) { return (a[w] & ~u[w]) != 0; });
  }

  const SelectionProblem& pb_;
  const SelectionObjective& objective_;
  std::uint64_t budget_;
  std::chrono::steady_clock::time_point deadline_;
  std::uint64_t nodes_ = 0;
  std::vector<VoxelSet> suffix_;
  std::vector<std::uint8_t> best_;
  double bestEnergy_ = 0.0;
};

// Best-improvement single flips from x until no flip improves. Coverage
// counts make each candidate flip one popcount pass over the item's words.
double descend(const SelectionProblem& pb, const SelectionObjective& objective,
               std::vector<std::uint8_t>& x) {
  const auto& items = pb.items();
  const std::size_t channels = pb.channelCount();
  CoverState united(pb.universe());
  std::size_t chosen = 0;
  ChannelCounts counts{};
  for (std::size_t a = 0; a < x.size(); ++a) {
    if (!x[a]) continue;
    for (std::size_t k = 0; k < channels; ++k)
      counts[k] += united.gain(items[a].parts[k], items[a].words);
    united.add(items[a].set, items[a].words);
    ++chosen;
  }
  // The counts after flipping item a.
  const auto flipped = [&](std::size_t a) {
    ChannelCounts c = counts;
    for (std::size_t k = 0; k < channels; ++k) {
      if (x[a]) {
        c[k] -= united.loss(items[a].parts[k], items[a].words);
      } else {
        c[k] += united.gain(items[a].parts[k], items[a].words);
      }
    }
    return c;
  };
  double e = objective.energy(chosen, counts);
  for (;;) {
    std::size_t bestFlip = x.size();
    double bestE = e - 1e-12;
    for (std::size_t a = 0; a < x.size(); ++a) {
      const double f = objective.energy(x[a] ? chosen - 1 : chosen + 1, flipped(a));
      if (f < bestE) bestE = f, bestFlip = a;
    }
    if (bestFlip == x.size()) return e;
    const std::size_t a = bestFlip;
    counts = flipped(a);
    if (x[a]) {
      united.remove(items[a].set, items[a].words);
      --chosen;
    } else {
      united.add(items[a].set, items[a].words);
      ++chosen;
    }
    x[a] ^= 1;
    e = objective.energy(chosen, counts);
  }
}

// The greedy descent from the empty selection, then `restarts` descents
// from the best so far with each item flipped with probability 1/4.
double localSearch(const SelectionProblem& pb, const SelectionObjective& objective,
                   const SelectionOptions& options, std::vector<std::uint8_t>& best) {
  const std::size_t n = pb.items().size();
  best.assign(n, 0);
  double bestE = descend(pb, objective, best);
  std::mt19937_64 rng(options.seed);
  for (int restart = 0; restart < options.restarts; ++restart) {
    std::vector<std::uint8_t> x = best;
    for (std::size_t a = 0; a < n; ++a) {
      if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) x[a] ^= 1;
    }
    const double e = descend(pb, objective, x);
    if (e < bestE - 1e-12) {
      bestE = e;
      best = x;
    }
  }
  return bestE;
}

std::uint64_t splitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

SelectionProblem::SelectionProblem(std::vector<VoxelSet> channels, std::size_t boundChannel)
    : channels_(std::move(channels)), boundChannel_(boundChannel) {
  assert(!channels_.empty() && channels_.size() <= ChannelCounts().size());
  assert(boundChannel_ < channels_.size());
}

bool SelectionProblem::add(VoxelSet set, std::uint32_t id) {
  assert(set.size() == universe());
  if (std::any_of(items_.begin(), items_.end(),
                  [&](const SelectionItem& item) { return item.set == set; })) {
    return false;
  }
  SelectionItem item;
  item.id = id;
  for (std::size_t k = 0; k < channels_.size(); ++k) item.parts[k] = set & channels_[k];
  item.words = nonZeroWords(set);
  item.set = std::move(set);
  items_.push_back(std::move(item));
  return true;
}

void SelectionProblem::sortByDescending(std::span<const double> score) {
  assert(score.size() == items_.size());
  std::vector<std::size_t> order(items_.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return score[a] > score[b]; });
  std::vector<SelectionItem> sorted;
  sorted.reserve(items_.size());
  for (std::size_t a : order) sorted.push_back(std::move(items_[a]));
  items_ = std::move(sorted);
}

ChannelCounts SelectionProblem::counts(const VoxelSet& united) const {
  ChannelCounts c{};
  for (std::size_t k = 0; k < channels_.size(); ++k)
    c[k] = VoxelSet::countAnd(united, channels_[k]);
  return c;
}

Selection solveSelection(const SelectionProblem& problem, const SelectionObjective& objective,
                         const SelectionOptions& options) {
  Selection s;
  s.energy = localSearch(problem, objective, options, s.chosen);
  BranchAndBound bb(problem, objective, options);
  s.provedOptimal = bb.run(s.chosen, s.energy);
  return s;
}

std::uint64_t streamSeed(std::uint64_t runSeed, std::uint64_t stream) {
  return stream ^ splitMix64(runSeed) ^ splitMix64(1);
}

}  // namespace csgvox
