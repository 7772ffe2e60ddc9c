#include "optimize/union_search.h"

#include <algorithm>
#include <bit>
#include <utility>

namespace csgvox {
namespace {

// |v| and |v ∩ inside| for v = (subtract ? base \ tool : base ∩ tool) ∪ rest,
// in one pass and without building v.
std::pair<std::size_t, std::size_t> cutCounts(const VoxelSet& base, const VoxelSet& tool,
                                              bool subtract, const VoxelSet& rest,
                                              const VoxelSet& inside) {
  const auto b = base.words(), t = tool.words(), r = rest.words(), in = inside.words();
  std::size_t all = 0, kept = 0;
  for (std::size_t w = 0; w < b.size(); ++w) {
    const std::uint64_t v = ((subtract ? b[w] & ~t[w] : b[w] & t[w]) | r[w]);
    all += std::size_t(std::popcount(v));
    kept += std::size_t(std::popcount(v & in[w]));
  }
  return {all, kept};
}

// A union under trial: the members it would have, by address (members of
// the current union, of `extra`, or changed copies), so that trying a move
// copies no voxel set.
using MemberRefs = std::vector<const UnionMember*>;

// |u| and |u ∩ inside| for u = a ∪ b, in one pass.
std::pair<std::size_t, std::size_t> unionCounts(const VoxelSet& a, const VoxelSet& b,
                                                const VoxelSet& inside) {
  const auto x = a.words(), y = b.words(), in = inside.words();
  std::size_t all = 0, kept = 0;
  for (std::size_t w = 0; w < x.size(); ++w) {
    all += std::size_t(std::popcount(x[w] | y[w]));
    kept += std::size_t(std::popcount((x[w] | y[w]) & in[w]));
  }
  return {all, kept};
}

// unionSearchEnergy from the counts: `prims` primitives, a union of `all`
// voxels of which `kept` are inside, `insideCount` inside voxels.
double energyOf(std::size_t prims, std::size_t all, std::size_t kept, std::size_t insideCount,
                double cost) {
  const std::size_t disagree = (all - kept) + (insideCount - kept);
  return cost * double(prims) + double(disagree);
}

double energyOf(const MemberRefs& members, const VoxelSet& inside, double cost) {
  VoxelSet u(inside.size());
  std::size_t prims = 0;
  for (const UnionMember* m : members) {
    u |= m->voxels;
    prims += memberPrimitives(*m);
  }
  const std::size_t disagree = VoxelSet::countAndNot(u, inside) + VoxelSet::countAndNot(inside, u);
  return cost * double(prims) + double(disagree);
}

// Removes members, one at a time (the first that lowers the energy, then
// again from the start), while that lowers the energy. The union without
// member i is the union of those before it and of those after it.
double pruneMembers(MemberRefs& members, const VoxelSet& inside, std::size_t insideCount,
                    double cost, double energy) {
  std::vector<VoxelSet> after;  // after[i]: the union of members i..
  for (bool improved = true; improved && members.size() > 1;) {
    improved = false;
    const std::size_t m = members.size();
    after.resize(m + 1);
    after[m] = VoxelSet(inside.size());
    std::size_t prims = 0;
    for (std::size_t i = m; i-- > 0;) {
      after[i] = after[i + 1];
      after[i] |= members[i]->voxels;
      prims += memberPrimitives(*members[i]);
    }
    VoxelSet before(inside.size());
    for (std::size_t i = 0; i < m; ++i) {
      const auto [all, kept] = unionCounts(before, after[i + 1], inside);
      const double e =
          energyOf(prims - memberPrimitives(*members[i]), all, kept, insideCount, cost);
      if (e < energy - 1e-9) {
        members.erase(members.begin() + long(i));
        energy = e;
        improved = true;
        break;
      }
      before |= members[i]->voxels;
    }
  }
  return energy;
}

MemberRefs refsOf(const std::vector<UnionMember>& members) {
  MemberRefs refs;
  for (const UnionMember& m : members) refs.push_back(&m);
  return refs;
}

// The members of `refs`, copied.
std::vector<UnionMember> copiesOf(const MemberRefs& refs) {
  std::vector<UnionMember> kept;
  for (const UnionMember* m : refs) kept.push_back(*m);
  return kept;
}

// The nonzero words of each member's voxels.
std::vector<std::vector<std::uint32_t>> nonzeroWords(std::span<const UnionMember> members) {
  std::vector<std::vector<std::uint32_t>> nonzero;
  for (const UnionMember& m : members) {
    std::vector<std::uint32_t> words;
    const auto v = m.voxels.words();
    for (std::size_t w = 0; w < v.size(); ++w) {
      if (v[w]) words.push_back(std::uint32_t(w));
    }
    nonzero.push_back(std::move(words));
  }
  return nonzero;
}

// The current union with each member left out, counted once for trying
// every extra member against it.
struct LeaveOneOut {
  std::size_t count = 0;          // members of the union
  std::size_t prims = 0;          // primitives of the whole union
  std::vector<VoxelSet> without;  // [i]: the union without member i; [count]: the whole union
  std::vector<std::pair<std::size_t, std::size_t>> withoutCounts;  // |without[i]|, its inside part
  std::vector<std::vector<std::uint32_t>> differs;  // words where without[i] and the union differ
};

// The union of `members` with each member left out in turn, and its counts.
LeaveOneOut leaveOneOut(const std::vector<UnionMember>& members, const VoxelSet& inside) {
  LeaveOneOut l;
  l.count = members.size();
  for (const UnionMember& m : members) l.prims += memberPrimitives(m);
  l.without.assign(l.count + 1, VoxelSet(inside.size()));
  for (std::size_t i = 0; i <= l.count; ++i) {
    for (std::size_t j = 0; j < l.count; ++j) {
      if (j != i) l.without[i] |= members[j].voxels;
    }
  }
  for (const VoxelSet& v : l.without) {
    l.withoutCounts.emplace_back(v.count(), VoxelSet::countAnd(v, inside));
  }
  const auto u = l.without[l.count].words();
  l.differs.resize(l.count);
  for (std::size_t i = 0; i < l.count; ++i) {
    const auto s = l.without[i].words();
    for (std::size_t w = 0; w < s.size(); ++w) {
      if (s[w] != u[w]) l.differs[i].push_back(std::uint32_t(w));
    }
  }
  return l;
}

// The best new or replaced action of a round, over all members and candidates.
struct BestAction {
  double energy = 0.0;
  std::size_t member = 0;
  std::size_t slot = std::size_t(-1);  // -1: a new action, else the action replaced
  SubtreeAction action;
  bool found = false;
};

// One searchUnion search: the union under refinement, what it may take in,
// and its current energy.
struct UnionSearcher {
  std::vector<UnionMember>& members;
  std::span<const UnionMember> extra;
  std::span<const DescriptionSet> d;
  const VoxelSet& inside;
  double cost;
  std::size_t insideCount = inside.count();
  double energy = unionSearchEnergy(members, inside, cost);
  // The nonzero words of each extra member's voxels.
  std::vector<std::vector<std::uint32_t>> extraWords = nonzeroWords(extra);

  // Makes the trial the union when its energy, once pruned, is lower.
  bool tryMove(MemberRefs trial, double e) {
    e = pruneMembers(trial, inside, insideCount, cost, e);
    if (e >= energy - 1e-9) return false;
    members = copiesOf(trial);
    energy = e;
    return true;
  }

  // Removes the members whose removal lowers the energy, before any move.
  void pruneCurrent() {
    MemberRefs all = refsOf(members);
    const double e = pruneMembers(all, inside, insideCount, cost, energy);
    if (all.size() != members.size()) members = copiesOf(all);
    energy = e;
  }

  // The current union with member i replaced by `changed`.
  MemberRefs replaced(std::size_t i, const UnionMember& changed) const {
    MemberRefs trial = refsOf(members);
    trial[i] = &changed;
    return trial;
  }

  // Drops one action of a member: the first drop that lowers the energy.
  bool dropAction() {
    for (std::size_t i = 0; i < members.size(); ++i) {
      for (std::size_t a = 0; a < members[i].actions.size(); ++a) {
        UnionMember m = members[i];
        m.actions.erase(m.actions.begin() + long(a));
        m.voxels = memberVoxels(m, d);
        const MemberRefs trial = replaced(i, m);
        if (tryMove(trial, energyOf(trial, inside, cost))) return true;
      }
    }
    return false;
  }

  // What extra[k]'s voxels add to `s` (its words) at word w, voxels and
  // inside ones.
  std::pair<std::int64_t, std::int64_t> added(std::span<const std::uint64_t> s, std::size_t k,
                                              std::size_t w) const {
    const auto in = inside.words();
    const std::uint64_t v = extra[k].voxels.words()[w];
    return std::pair{std::int64_t(std::popcount(s[w] | v) - std::popcount(s[w])),
                     std::int64_t(std::popcount((s[w] | v) & in[w]) - std::popcount(s[w] & in[w]))};
  }

  // The counts of without[i] ∪ extra[k] (i = count: the whole union), from
  // what extra[k] adds to the whole union (`toUnion`) and, where without[i]
  // differs from it, the difference.
  std::pair<std::size_t, std::size_t> countsWith(const LeaveOneOut& l,
                                                 std::pair<std::int64_t, std::int64_t> toUnion,
                                                 std::size_t i, std::size_t k) const {
    auto [all, kept] = toUnion;
    if (i < l.count) {
      const auto u = l.without[l.count].words();
      const auto s = l.without[i].words();
      for (std::uint32_t w : l.differs[i]) {
        const auto [a0, k0] = added(u, k, w);
        const auto [a1, k1] = added(s, k, w);
        all += a1 - a0;
        kept += k1 - k0;
      }
    }
    return std::pair{std::size_t(std::int64_t(l.withoutCounts[i].first) + all),
                     std::size_t(std::int64_t(l.withoutCounts[i].second) + kept)};
  }

  // Tries extra[k] as a new member: the trial union and pruneMembers' first
  // pass over it (the trial without each member) are counted from `l`, plus
  // the words of extra[k]'s voxels.
  bool tryExtra(const LeaveOneOut& l, std::size_t k) {
    const bool present = std::any_of(members.begin(), members.end(), [&](const UnionMember& m) {
      return m.root == extra[k].root && m.actions == extra[k].actions;
    });
    if (present || VoxelSet::countAnd(extra[k].voxels, inside) == 0) return false;
    std::pair<std::int64_t, std::int64_t> toUnion{0, 0};
    const auto u = l.without[l.count].words();
    for (std::uint32_t w : extraWords[k]) {
      const auto [a, b] = added(u, k, w);
      toUnion.first += a;
      toUnion.second += b;
    }
    const std::size_t withK = l.prims + memberPrimitives(extra[k]);
    const auto [all, kept] = countsWith(l, toUnion, l.count, k);
    const double e = energyOf(withK, all, kept, insideCount, cost);
    MemberRefs trial = refsOf(members);
    trial.push_back(&extra[k]);
    // pruneMembers' first pass: the first member whose removal lowers e.
    std::size_t first = trial.size();
    double firstEnergy = e;
    for (std::size_t i = 0; i < trial.size() && trial.size() > 1; ++i) {
      double ei = 0.0;
      if (i < l.count) {
        const auto [a, b] = countsWith(l, toUnion, i, k);
        ei = energyOf(withK - memberPrimitives(members[i]), a, b, insideCount, cost);
      } else {
        ei = energyOf(l.prims, l.withoutCounts[l.count].first, l.withoutCounts[l.count].second,
                      insideCount, cost);
      }
      if (ei < e - 1e-9) {
        first = i;
        firstEnergy = ei;
        break;
      }
    }
    if (first == trial.size()) return e < energy - 1e-9 && tryMove(trial, e);
    trial.erase(trial.begin() + long(first));
    return tryMove(trial, firstEnergy);
  }

  // Adds one of `extra` as a member: the first that lowers the energy once
  // pruned.
  bool tryExtras() {
    const LeaveOneOut l = leaveOneOut(members, inside);
    for (std::size_t k = 0; k < extra.size(); ++k) {
      if (tryExtra(l, k)) return true;
    }
    return false;
  }

  // Offers `best` every new action of member i and every replacement of one
  // of its actions' candidates, for a union of `prims` primitives.
  void offerActions(std::size_t i, std::size_t prims, BestAction& best) const {
    const UnionMember& m = members[i];
    VoxelSet rest(inside.size());
    for (std::size_t j = 0; j < members.size(); ++j) {
      if (j != i) rest |= members[j].voxels;
    }
    // Tries `base` (the member's voxels without the changed slot) cut by
    // candidate k, as the action in `slot`, with `count` primitives.
    const auto tryAction = [&](const VoxelSet& base, std::size_t slot, std::uint32_t k,
                               bool subtract, std::size_t count) {
      const auto [all, kept] = cutCounts(base, d[k].voxels, subtract, rest, inside);
      const double e = cost * double(count) + double(all + insideCount) - 2.0 * double(kept);
      if (e < best.energy) best = BestAction{e, i, slot, SubtreeAction{k, subtract}, true};
    };
    for (std::uint32_t k = 0; k < d.size(); ++k) {
      if (k == m.root || !VoxelSet::intersects(d[k].voxels, m.voxels)) continue;
      for (const bool subtract : {true, false}) {
        tryAction(m.voxels, std::size_t(-1), k, subtract, prims + 1);
      }
    }
    // Or the best replacement of one action's candidate by another, with
    // the same operation (a better fit of the same surface).
    for (std::size_t a = 0; a < m.actions.size(); ++a) {
      const SubtreeAction old = m.actions[a];
      const VoxelSet without = memberVoxels(m, d, a);
      for (std::uint32_t k = 0; k < d.size(); ++k) {
        if (k == old.primitive || k == m.root || !VoxelSet::intersects(d[k].voxels, without)) {
          continue;
        }
        tryAction(without, a, k, old.subtract, prims);
      }
    }
  }

  // Makes the best new or replaced action over all members and candidates,
  // when it lowers the energy.
  bool bestActionMove() {
    std::size_t prims = 0;
    for (const UnionMember& m : members) prims += memberPrimitives(m);
    BestAction best;
    best.energy = energy - 1e-9;
    for (std::size_t i = 0; i < members.size(); ++i) offerActions(i, prims, best);
    if (!best.found) return false;
    UnionMember m = members[best.member];
    if (best.slot == std::size_t(-1)) {
      m.actions.push_back(best.action);
    } else {
      m.actions[best.slot] = best.action;
    }
    m.voxels = memberVoxels(m, d);
    const MemberRefs trial = replaced(best.member, m);
    return tryMove(trial, energyOf(trial, inside, cost));
  }
};

}  // namespace

double unionSearchEnergy(std::span<const UnionMember> members, const VoxelSet& inside,
                         double cost) {
  MemberRefs refs;
  for (const UnionMember& m : members) refs.push_back(&m);
  return energyOf(refs, inside, cost);
}

void searchUnion(std::vector<UnionMember>& members, std::span<const UnionMember> extra,
                 std::span<const DescriptionSet> d, const VoxelSet& inside, double cost) {
  UnionSearcher r{members, extra, d, inside, cost};
  r.pruneCurrent();
  for (bool improved = true; improved;) {
    improved = r.dropAction() || r.tryExtras() || r.bestActionMove();
  }
}

}  // namespace csgvox
