#include "optimize/branch_and_bound.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <limits>
#include <numeric>
#include <random>

#include "optimize/class_cover.h"
#include "optimize/selection_classes.h"

namespace csgvox {
namespace {

// Depth-first over the items in order: at item t, include it (when it adds
// voxels of the bound channel) or not. A node is cut when the objective's
// bound, over everything the remaining items could add, cannot beat the best
// energy found. The union is kept as a bitset over the classes, so a node
// costs a pass over a few dozen words and the classes its item newly covers,
// whatever the number of voxels.
class BranchAndBound {
 public:
  BranchAndBound(const SelectionClasses& classes, std::size_t boundChannel,
                 const SelectionObjective& objective, const SelectionOptions& options)
      : classes_(classes),
        objective_(objective),
        n_(classes.itemCount()),
        boundChannel_(boundChannel),
        budget_(options.nodeBudget),
        control_(options.control),
        classWords_((classes.size() + 63) / 64),
        united_(classWords_, 0),
        itemBits_(n_ * classWords_, 0),
        newly_(n_ * classWords_, 0) {
    for (std::size_t t = 0; t < n_; ++t) {
      for (std::uint32_t c : classes.classesOf(t)) {
        itemBits_[t * classWords_ + c / 64] |= std::uint64_t(1) << (c % 64);
      }
    }
    // A class is in the suffix of items t.. while t is at most its last item:
    // ending_[t] lists the classes (of the bound channel) whose last item is t.
    std::vector<std::size_t> perItem(n_ + 1, 0);
    for (std::size_t c = 0; c < classes.size(); ++c) {
      if (boundWeight(c) > 0) ++perItem[classes.itemsOf(c).back() + 1];
    }
    endingStart_.assign(n_ + 1, 0);
    for (std::size_t t = 0; t < n_; ++t) endingStart_[t + 1] = endingStart_[t] + perItem[t + 1];
    ending_.resize(endingStart_[n_]);
    std::vector<std::size_t> next(endingStart_.begin(), endingStart_.end() - 1);
    for (std::size_t c = 0; c < classes.size(); ++c) {
      if (boundWeight(c) > 0) ending_[next[classes.itemsOf(c).back()]++] = std::uint32_t(c);
    }
    suffix_.assign(n_ + 1, 0);
    for (std::size_t t = n_; t-- > 0;) {
      suffix_[t] = suffix_[t + 1];
      for (std::size_t e = endingStart_[t]; e < endingStart_[t + 1]; ++e) {
        suffix_[t] += boundWeight(ending_[e]);
      }
    }
  }

  // Returns true when the search finished within the budget.
  bool run(std::vector<std::uint8_t>& best, double& bestEnergy) {
    best_ = best;
    bestEnergy_ = bestEnergy;
    std::vector<std::uint8_t> current(n_, 0);
    search(0, 0, 0, current);
    best = best_;
    bestEnergy = bestEnergy_;
    return nodes_ <= budget_;
  }

 private:
  std::size_t boundWeight(std::size_t c) const { return classes_.weight(c)[boundChannel_]; }

  // `coveredOut`: voxels of the bound channel the union holds beyond the
  // reach of items t.. (in classes whose last item is before t).
  void search(std::size_t t, std::size_t chosen, std::size_t coveredOut,
              std::vector<std::uint8_t>& current) {
    if (++nodes_ > budget_) return;
    // The clock is read every 1024 nodes; past the deadline (or once
    // cancelled) the search ends as if the budget were spent.
    if ((nodes_ & 1023) == 0 && control_.shouldStop()) {
      budget_ = nodes_ - 1;
      return;
    }
    const double e = objective_.energy(chosen, counts_);
    if (e < bestEnergy_ - 1e-12) {
      bestEnergy_ = e;
      best_ = current;
    }
    if (t == n_) return;
    // |(union ∩ bound channel) ∪ suffix|: the most of the bound channel any
    // completion can hold.
    const std::size_t reach = suffix_[t] + coveredOut;
    if (objective_.bound(chosen, counts_, reach) >= bestEnergy_ - 1e-12) return;
    // Include t when it adds a voxel of the bound channel.
    const ChannelCounts before = counts_;
    std::uint64_t* newly = newly_.data() + t * classWords_;
    const std::uint64_t* item = itemBits_.data() + t * classWords_;
    for (std::size_t w = 0; w < classWords_; ++w) {
      newly[w] = item[w] & ~united_[w];
      for (std::uint64_t bits = newly[w]; bits; bits &= bits - 1) {
        const ChannelCounts& weight = classes_.weight(w * 64 + std::size_t(std::countr_zero(bits)));
        for (std::size_t k = 0; k < counts_.size(); ++k) counts_[k] += weight[k];
      }
      united_[w] |= newly[w];
    }
    if (counts_[boundChannel_] > before[boundChannel_]) {
      current[t] = 1;
      search(t + 1, chosen + 1, coveredOut + endingCovered(t), current);
      current[t] = 0;
    }
    for (std::size_t w = 0; w < classWords_; ++w) united_[w] &= ~newly[w];
    counts_ = before;
    search(t + 1, chosen, coveredOut + endingCovered(t), current);
  }

  // Voxels of the bound channel in the covered classes whose last item is t.
  std::size_t endingCovered(std::size_t t) const {
    std::size_t n = 0;
    for (std::size_t e = endingStart_[t]; e < endingStart_[t + 1]; ++e) {
      const std::uint32_t c = ending_[e];
      if (united_[c / 64] >> (c % 64) & 1) n += boundWeight(c);
    }
    return n;
  }

  const SelectionClasses& classes_;
  const SelectionObjective& objective_;
  std::size_t n_;
  std::size_t boundChannel_;
  std::uint64_t budget_;
  RunControl control_;
  std::uint64_t nodes_ = 0;
  std::size_t classWords_;                // 64-bit words of a bitset over the classes
  std::vector<std::uint64_t> united_;     // classes the current selection holds
  std::vector<std::uint64_t> itemBits_;   // item t's classes: words [t, t + 1) * classWords_
  std::vector<std::uint64_t> newly_;      // at depth t, the classes item t added
  ChannelCounts counts_{};                // the current union's voxels per channel
  std::vector<std::size_t> suffix_;       // bound-channel voxels items t.. can reach
  std::vector<std::size_t> endingStart_;  // ending_ of item t: [endingStart_[t], endingStart_[t+1])
  std::vector<std::uint32_t> ending_;
  std::vector<std::uint8_t> best_;
  double bestEnergy_ = 0.0;
};

// Best-improvement single flips from x until no flip improves. The cover
// caches every item's flip effect, so weighing all flips costs one energy
// evaluation per item.
double descend(const SelectionObjective& objective, ClassCover& cover,
               std::vector<std::uint8_t>& x) {
  cover.reset(x);
  std::size_t chosen = std::size_t(std::count(x.begin(), x.end(), std::uint8_t(1)));
  double e = objective.energy(chosen, cover.counts());
  for (;;) {
    std::size_t bestFlip = x.size();
    double bestE = e - 1e-12;
    for (std::size_t a = 0; a < x.size(); ++a) {
      const double f = objective.energy(x[a] ? chosen - 1 : chosen + 1, cover.countsAfterFlip(a));
      if (f < bestE) bestE = f, bestFlip = a;
    }
    if (bestFlip == x.size()) return e;
    const std::size_t a = bestFlip;
    chosen = x[a] ? chosen - 1 : chosen + 1;
    cover.flip(a);
    x[a] ^= 1;
    e = objective.energy(chosen, cover.counts());
  }
}

// The greedy descent from the empty selection, then `restarts` descents
// from the best so far with each item flipped with probability 1/4.
double localSearch(const SelectionClasses& classes, const SelectionObjective& objective,
                   const SelectionOptions& options, std::vector<std::uint8_t>& best) {
  const std::size_t n = classes.itemCount();
  ClassCover cover(classes);
  best.assign(n, 0);
  double bestE = descend(objective, cover, best);
  std::mt19937_64 rng(options.seed);
  for (int restart = 0; restart < options.restarts; ++restart) {
    std::vector<std::uint8_t> x = best;
    for (std::size_t a = 0; a < n; ++a) {
      if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) x[a] ^= 1;
    }
    const double e = descend(objective, cover, x);
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
  items_.push_back(SelectionItem{id, std::move(set)});
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
  return solveSelection(SelectionClasses(problem), problem.boundChannel(), objective, options);
}

Selection solveSelection(const SelectionClasses& classes, std::size_t boundChannel,
                         const SelectionObjective& objective, const SelectionOptions& options) {
  Selection s;
  s.energy = localSearch(classes, objective, options, s.chosen);
  BranchAndBound bb(classes, boundChannel, objective, options);
  s.provedOptimal = bb.run(s.chosen, s.energy);
  return s;
}

std::uint64_t streamSeed(std::uint64_t runSeed, std::uint64_t stream) {
  return stream ^ splitMix64(runSeed) ^ splitMix64(1);
}

}  // namespace csgvox
