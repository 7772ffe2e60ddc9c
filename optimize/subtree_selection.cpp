#include "optimize/subtree_selection.h"

#include "optimize/cover_state.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <limits>
#include <numeric>
#include <random>

namespace csgvox {
namespace {

// The problem restricted to the root's own voxels (the "universe"): every
// action removes a set of the root's voxels; the truncated root keeps what no
// chosen action removes.
struct LocalProblem {
  std::size_t universe = 0;
  VoxelSet inside;                 // I ∩ root, local
  VoxelSet outside;                // root \ I, local
  std::vector<VoxelSet> removes;   // per useful action: the voxels it removes
  std::vector<VoxelSet> removesOut;  // ∩ outside
  std::vector<VoxelSet> removesIn;   // ∩ inside
  std::vector<std::size_t> actionIndex;  // useful action -> index 2i (+1 for subtract)
  std::vector<std::vector<std::uint32_t>> words;  // per action: non-zero words of `removes`
  std::size_t insideCount = 0, outsideCount = 0;
  double invL = 0.0, alpha = 0.9;

  double energy(std::size_t chosen, const VoxelSet& removed) const {
    const double num = double(insideCount - VoxelSet::countAnd(removed, inside));
    const double den = double(insideCount + outsideCount - VoxelSet::countAnd(removed, outside));
    return double(chosen) * invL - alpha * (den > 0.0 ? num / den : 0.0);
  }
};

class BranchAndBound {
 public:
  BranchAndBound(const LocalProblem& pb, std::uint64_t budget,
                 std::chrono::steady_clock::time_point deadline)
      : pb_(pb), budget_(budget), deadline_(deadline) {
    const std::size_t n = pb.removes.size();
    suffixOut_.assign(n + 1, VoxelSet(pb.universe));
    for (std::size_t t = n; t-- > 0;) suffixOut_[t] = suffixOut_[t + 1] | pb.removesOut[t];
  }

  // Returns true when the search finished within the budget.
  bool run(std::vector<std::uint8_t>& best, double& bestEnergy) {
    best_ = best;
    bestEnergy_ = bestEnergy;
    std::vector<std::uint8_t> current(pb_.removes.size(), 0);
    VoxelSet removed(pb_.universe);
    search(0, 0, removed, current);
    best = best_;
    bestEnergy = bestEnergy_;
    return nodes_ <= budget_;
  }

 private:
  void search(std::size_t t, std::size_t chosen, const VoxelSet& removed,
              std::vector<std::uint8_t>& current) {
    if (++nodes_ > budget_) return;
    // The clock is read every 1024 nodes; past the deadline the search ends
    // as if the budget were spent.
    if ((nodes_ & 1023) == 0 && std::chrono::steady_clock::now() > deadline_) {
      budget_ = nodes_ - 1;
      return;
    }
    const double e = pb_.energy(chosen, removed);
    if (e < bestEnergy_ - 1e-12) {
      bestEnergy_ = e;
      best_ = current;
    }
    if (t == pb_.removes.size()) return;
    // Bound: the inside kept can only shrink, the outside kept can shrink at
    // most to what the remaining actions cannot remove; each further action
    // costs 1/L.
    const double num = double(pb_.insideCount - VoxelSet::countAnd(removed, pb_.inside));
    const VoxelSet removedOut = removed & pb_.outside;
    const double den = double(pb_.insideCount + pb_.outsideCount -
                              VoxelSet::countOr(removedOut, suffixOut_[t]));
    const double bound = double(chosen) * pb_.invL - pb_.alpha * (den > 0.0 ? num / den : 0.0);
    if (bound >= bestEnergy_ - 1e-12) return;
    // Include action t when it removes outside voxels not yet removed.
    if (VoxelSet::countAndNot(pb_.removesOut[t], removedOut) > 0) {
      current[t] = 1;
      search(t + 1, chosen + 1, removed | pb_.removes[t], current);
      current[t] = 0;
    }
    search(t + 1, chosen, removed, current);
  }

  const LocalProblem& pb_;
  std::uint64_t budget_;
  std::chrono::steady_clock::time_point deadline_;
  std::uint64_t nodes_ = 0;
  std::vector<VoxelSet> suffixOut_;
  std::vector<std::uint8_t> best_;
  double bestEnergy_ = 0.0;
};

// Best-improvement single flips from x until no flip improves. Coverage
// counts make each candidate flip one popcount pass over the universe.
double descend(const LocalProblem& pb, std::vector<std::uint8_t>& x) {
  CoverState removed(pb.universe);
  std::size_t chosen = 0, lostIn = 0, lostOut = 0;
  for (std::size_t a = 0; a < x.size(); ++a) {
    if (!x[a]) continue;
    lostIn += removed.gain(pb.removesIn[a], pb.words[a]);
    lostOut += removed.gain(pb.removesOut[a], pb.words[a]);
    removed.add(pb.removes[a], pb.words[a]);
    ++chosen;
  }
  const auto energyOf = [&](std::size_t c, std::size_t in, std::size_t out) {
    const double num = double(pb.insideCount - in);
    const double den = double(pb.insideCount + pb.outsideCount - out);
    return double(c) * pb.invL - pb.alpha * (den > 0.0 ? num / den : 0.0);
  };
  double e = energyOf(chosen, lostIn, lostOut);
  for (;;) {
    std::size_t bestFlip = x.size();
    double bestE = e - 1e-12;
    for (std::size_t a = 0; a < x.size(); ++a) {
      const double f =
          x[a] ? energyOf(chosen - 1, lostIn - removed.loss(pb.removesIn[a], pb.words[a]),
                          lostOut - removed.loss(pb.removesOut[a], pb.words[a]))
               : energyOf(chosen + 1, lostIn + removed.gain(pb.removesIn[a], pb.words[a]),
                          lostOut + removed.gain(pb.removesOut[a], pb.words[a]));
      if (f < bestE) bestE = f, bestFlip = a;
    }
    if (bestFlip == x.size()) return e;
    const std::size_t a = bestFlip;
    if (x[a]) {
      lostIn -= removed.loss(pb.removesIn[a], pb.words[a]);
      lostOut -= removed.loss(pb.removesOut[a], pb.words[a]);
      removed.remove(pb.removes[a], pb.words[a]);
      --chosen;
    } else {
      lostIn += removed.gain(pb.removesIn[a], pb.words[a]);
      lostOut += removed.gain(pb.removesOut[a], pb.words[a]);
      removed.add(pb.removes[a], pb.words[a]);
      ++chosen;
    }
    x[a] ^= 1;
    e = energyOf(chosen, lostIn, lostOut);
  }
}

double localSearch(const LocalProblem& pb, std::vector<std::uint8_t>& best) {
  const std::size_t n = pb.removes.size();
  best.assign(n, 0);
  double bestE = descend(pb, best);
  std::mt19937_64 rng(12345);
  for (int restart = 0; restart < 3; ++restart) {
    std::vector<std::uint8_t> x = best;
    for (std::size_t a = 0; a < n; ++a) {
      if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) x[a] ^= 1;
    }
    const double e = descend(pb, x);
    if (e < bestE - 1e-12) {
      bestE = e;
      best = x;
    }
  }
  return bestE;
}

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
  // Work on the root's own voxels only.
  const std::vector<std::uint32_t> positions = root.members();
  LocalProblem pb;
  pb.universe = positions.size();
  pb.alpha = options.alpha;
  pb.inside = inside.gather(positions);
  pb.outside = pb.inside.complemented();
  pb.insideCount = pb.inside.count();
  if (options.minFeatureVoxels > 0.0) {
    pb.invL = options.minFeatureVoxels / double(std::max<std::size_t>(1, pb.insideCount));
  } else {
    pb.invL = result.actionCount ? 1.0 / double(result.actionCount) : 0.0;
  }
  pb.outsideCount = pb.universe - pb.insideCount;
  // Useful actions: those removing at least one outside voxel; an action that
  // removes only inside voxels never belongs to an optimum. Actions with the
  // same effect are kept once.
  for (std::size_t i = 0; i < neighbours.size() && pb.outsideCount > 0; ++i) {
    const VoxelSet local = neighbours[i]->gather(positions);
    for (int sub = 0; sub < 2; ++sub) {
      VoxelSet removes = sub ? local : local.complemented();
      VoxelSet removesOut = removes & pb.outside;
      if (removesOut.none()) continue;
      // An action removing k outside voxels improves the fit term by at most
      // alpha * k / |V+(root)| in any solution (the denominator never drops
      // below |V+(root)|, the numerator never exceeds it) and costs
      // minFeatureVoxels / |V+(root)|: when alpha * k <= minFeatureVoxels it
      // never pays for itself, so no optimum holds it. Exact, and on noisy
      // labels it drops most actions.
      if (options.minFeatureVoxels > 0.0 &&
          pb.alpha * double(removesOut.count()) <= options.minFeatureVoxels) {
        continue;
      }
      const bool duplicate = std::any_of(pb.removes.begin(), pb.removes.end(),
                                         [&](const VoxelSet& r) { return r == removes; });
      if (duplicate) continue;
      pb.removesIn.push_back(removes & pb.inside);
      pb.removes.push_back(std::move(removes));
      pb.removesOut.push_back(std::move(removesOut));
      pb.actionIndex.push_back(2 * i + std::size_t(sub));
    }
  }
  result.usefulActions = pb.removes.size();
  // Order: most outside removed per inside lost first (good incumbents early).
  std::vector<std::size_t> order(pb.removes.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<double> score(order.size());
  for (std::size_t a = 0; a < order.size(); ++a) {
    const double out = double(pb.removesOut[a].count());
    score[a] = out / (1.0 + double(pb.removes[a].count()) - out);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return score[a] > score[b];
  });
  LocalProblem sorted;
  sorted.universe = pb.universe;
  sorted.inside = std::move(pb.inside);
  sorted.outside = std::move(pb.outside);
  sorted.insideCount = pb.insideCount;
  sorted.outsideCount = pb.outsideCount;
  sorted.invL = pb.invL;
  sorted.alpha = pb.alpha;
  for (std::size_t a : order) {
    sorted.removes.push_back(std::move(pb.removes[a]));
    sorted.removesOut.push_back(std::move(pb.removesOut[a]));
    sorted.removesIn.push_back(std::move(pb.removesIn[a]));
    sorted.actionIndex.push_back(pb.actionIndex[a]);
    sorted.words.push_back(nonZeroWords(sorted.removes.back()));
  }

  std::vector<std::uint8_t> best;
  double bestEnergy = localSearch(sorted, best);
  BranchAndBound bb(sorted, options.nodeBudget, options.deadline);
  result.provedOptimal = bb.run(best, bestEnergy);
  result.energy = bestEnergy;
  result.voxels = root;
  for (std::size_t a = 0; a < best.size(); ++a) {
    if (!best[a]) continue;
    const std::size_t idx = sorted.actionIndex[a];
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
