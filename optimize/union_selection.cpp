#include "optimize/union_selection.h"

#include "optimize/cover_state.h"

#include <algorithm>
#include <numeric>
#include <random>

namespace csgvox {
namespace {

struct Problem {
  const VoxelSet* inside = nullptr;
  std::vector<VoxelSet> covers;  // V(C_i) ∩ V+(P), useful candidates only
  std::vector<std::uint32_t> ids;
  double invM = 0.0, beta = 0.9, invTotal = 0.0;

  double energy(std::size_t chosen, std::size_t covered) const {
    return double(chosen) * invM - beta * double(covered) * invTotal;
  }
};

class BranchAndBound {
 public:
  BranchAndBound(const Problem& pb, std::uint64_t budget,
                 std::chrono::steady_clock::time_point deadline)
      : pb_(pb), budget_(budget), deadline_(deadline) {
    const std::size_t n = pb.covers.size();
    suffix_.assign(n + 1, VoxelSet(pb.inside->size()));
    for (std::size_t t = n; t-- > 0;) suffix_[t] = suffix_[t + 1] | pb.covers[t];
  }

  bool run(std::vector<std::uint8_t>& best, double& bestEnergy) {
    best_ = best;
    bestEnergy_ = bestEnergy;
    std::vector<std::uint8_t> current(pb_.covers.size(), 0);
    search(0, 0, VoxelSet(pb_.inside->size()), current);
    best = best_;
    bestEnergy = bestEnergy_;
    return nodes_ <= budget_;
  }

 private:
  void search(std::size_t t, std::size_t chosen, const VoxelSet& covered,
              std::vector<std::uint8_t>& current) {
    if (++nodes_ > budget_) return;
    // The clock is read every 1024 nodes; past the deadline the search ends
    // as if the budget were spent.
    if ((nodes_ & 1023) == 0 && std::chrono::steady_clock::now() > deadline_) {
      budget_ = nodes_ - 1;
      return;
    }
    const std::size_t have = covered.count();
    const double e = pb_.energy(chosen, have);
    if (e < bestEnergy_ - 1e-12) {
      bestEnergy_ = e;
      best_ = current;
    }
    if (t == pb_.covers.size()) return;
    // Bound: everything the remaining candidates could add, for at least one
    // more candidate.
    const std::size_t reach = VoxelSet::countOr(covered, suffix_[t]);
    if (reach == have) return;
    if (pb_.energy(chosen + 1, reach) >= bestEnergy_ - 1e-12) return;
    if (VoxelSet::countAndNot(pb_.covers[t], covered) > 0) {
      current[t] = 1;
      search(t + 1, chosen + 1, covered | pb_.covers[t], current);
      current[t] = 0;
    }
    search(t + 1, chosen, covered, current);
  }

  const Problem& pb_;
  std::uint64_t budget_;
  std::chrono::steady_clock::time_point deadline_;
  std::uint64_t nodes_ = 0;
  std::vector<VoxelSet> suffix_;
  std::vector<std::uint8_t> best_;
  double bestEnergy_ = 0.0;
};

// Best-improvement single flips from z until no flip improves, with
// incremental coverage counts: each candidate flip costs one popcount pass.
double descend(const Problem& pb, std::vector<std::uint8_t>& z) {
  CoverState state(pb.inside->size());
  std::size_t chosen = 0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    if (z[i]) state.add(pb.covers[i]), ++chosen;
  }
  std::size_t covered = state.covered().count();
  for (;;) {
    std::size_t bestFlip = z.size();
    double bestDelta = -1e-12;
    for (std::size_t i = 0; i < z.size(); ++i) {
      const double delta =
          z[i] ? -pb.invM + pb.beta * double(state.loss(pb.covers[i])) * pb.invTotal
               : pb.invM - pb.beta * double(state.gain(pb.covers[i])) * pb.invTotal;
      if (delta < bestDelta) bestDelta = delta, bestFlip = i;
    }
    if (bestFlip == z.size()) return pb.energy(chosen, covered);
    if (z[bestFlip]) {
      covered -= state.loss(pb.covers[bestFlip]);
      state.remove(pb.covers[bestFlip]);
      --chosen;
    } else {
      covered += state.gain(pb.covers[bestFlip]);
      state.add(pb.covers[bestFlip]);
      ++chosen;
    }
    z[bestFlip] ^= 1;
  }
}

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
  Problem pb;
  pb.beta = options.beta;
  const std::size_t total = inside.count();
  if (options.minFeatureVoxels > 0.0) {
    pb.invM = options.minFeatureVoxels / double(std::max<std::size_t>(1, total));
  } else {
    pb.invM = candidates.empty() ? 0.0 : 1.0 / double(candidates.size());
  }
  pb.invTotal = total ? 1.0 / double(total) : 0.0;
  // Work on the inside voxels only. Candidates covering nothing, or exactly
  // what an earlier one covers, never improve an optimum.
  const std::vector<std::uint32_t> positions = inside.members();
  const VoxelSet local = VoxelSet(positions.size()).complemented();
  pb.inside = &local;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    VoxelSet c = candidates[i]->gather(positions);
    if (c.none()) continue;
    if (std::any_of(pb.covers.begin(), pb.covers.end(), [&](const VoxelSet& o) { return o == c; })) {
      continue;
    }
    pb.covers.push_back(std::move(c));
    pb.ids.push_back(std::uint32_t(i));
  }
  // Largest first: good incumbents early, strong suffix bounds.
  std::vector<std::size_t> order(pb.covers.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<std::size_t> sizes(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) sizes[i] = pb.covers[i].count();
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return sizes[a] > sizes[b]; });
  Problem sorted;
  sorted.inside = pb.inside;
  sorted.invM = pb.invM;
  sorted.beta = pb.beta;
  sorted.invTotal = pb.invTotal;
  for (std::size_t i : order) {
    sorted.covers.push_back(std::move(pb.covers[i]));
    sorted.ids.push_back(pb.ids[i]);
  }
  // Incumbent: greedy descent, then restarts.
  std::vector<std::uint8_t> best(sorted.covers.size(), 0);
  double bestEnergy = descend(sorted, best);
  std::mt19937_64 rng(54321);
  for (int restart = 0; restart < 8 && !best.empty(); ++restart) {
    std::vector<std::uint8_t> z = best;
    for (auto& b : z) {
      if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) b ^= 1;
    }
    const double e = descend(sorted, z);
    if (e < bestEnergy - 1e-12) bestEnergy = e, best = z;
  }
  BranchAndBound bb(sorted, options.nodeBudget, options.deadline);
  result.provedOptimal = bb.run(best, bestEnergy);
  result.energy = bestEnergy;
  VoxelSet covered(local.size());
  for (std::size_t i = 0; i < best.size(); ++i) {
    if (best[i]) {
      result.chosen.push_back(sorted.ids[i]);
      covered |= sorted.covers[i];
    }
  }
  std::sort(result.chosen.begin(), result.chosen.end());
  result.covered = covered.count();
  return result;
}

}  // namespace csgvox
