#include "optimize/union_refinement.h"

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

// refinementEnergy from the counts: `prims` primitives, a union of `all`
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

}  // namespace

double refinementEnergy(std::span<const UnionMember> members, const VoxelSet& inside, double cost) {
  MemberRefs refs;
  for (const UnionMember& m : members) refs.push_back(&m);
  return energyOf(refs, inside, cost);
}

void refineUnion(std::vector<UnionMember>& members, std::span<const UnionMember> extra,
                 std::span<const DescriptionSet> d, const VoxelSet& inside, double cost) {
  const std::size_t insideCount = inside.count();
  // Makes the trial the union when its energy, once pruned, is lower.
  double energy = refinementEnergy(members, inside, cost);
  const auto tryMove = [&](MemberRefs trial, double e) {
    e = pruneMembers(trial, inside, insideCount, cost, e);
    if (e >= energy - 1e-9) return false;
    std::vector<UnionMember> kept;
    for (const UnionMember* m : trial) kept.push_back(*m);
    members = std::move(kept);
    energy = e;
    return true;
  };
  {
    MemberRefs all = refsOf(members);
    const double e = pruneMembers(all, inside, insideCount, cost, energy);
    if (all.size() != members.size()) {
      std::vector<UnionMember> kept;
      for (const UnionMember* m : all) kept.push_back(*m);
      members = std::move(kept);
    }
    energy = e;
  }
  // The current union with member i replaced by `changed`.
  const auto replaced = [&](std::size_t i, const UnionMember& changed) {
    MemberRefs trial = refsOf(members);
    trial[i] = &changed;
    return trial;
  };
  // Nonzero words of each extra member's voxels.
  std::vector<std::vector<std::uint32_t>> extraWords;
  for (const UnionMember& m : extra) {
    std::vector<std::uint32_t> words;
    const auto v = m.voxels.words();
    for (std::size_t w = 0; w < v.size(); ++w) {
      if (v[w]) words.push_back(std::uint32_t(w));
    }
    extraWords.push_back(std::move(words));
  }
  // Adds one of `extra` as a member: the first that lowers the energy once
  // pruned. The trial union and the first pruning pass over it (the trial
  // without each member) are counted from the union without each member,
  // computed once, plus the words of the extra member's voxels.
  const auto tryExtras = [&]() {
    const std::size_t count = members.size();
    std::size_t prims = 0;
    for (const UnionMember& m : members) prims += memberPrimitives(m);
    std::vector<VoxelSet> without(count + 1,
                                  VoxelSet(inside.size()));  // [count]: no member left out
    for (std::size_t i = 0; i <= count; ++i) {
      for (std::size_t j = 0; j < count; ++j) {
        if (j != i) without[i] |= members[j].voxels;
      }
    }
    std::vector<std::pair<std::size_t, std::size_t>> withoutCounts;
    for (const VoxelSet& v : without) {
      withoutCounts.emplace_back(v.count(), VoxelSet::countAnd(v, inside));
    }
    const auto in = inside.words();
    const auto u = without[count].words();
    // Words where the union without member i differs from the whole union.
    std::vector<std::vector<std::uint32_t>> differs(count);
    for (std::size_t i = 0; i < count; ++i) {
      const auto s = without[i].words();
      for (std::size_t w = 0; w < s.size(); ++w) {
        if (s[w] != u[w]) differs[i].push_back(std::uint32_t(w));
      }
    }
    // What extra[k]'s voxels add to `s` (its words), voxels and inside ones.
    const auto added = [&](std::span<const std::uint64_t> s, std::size_t k, std::size_t w) {
      const std::uint64_t v = extra[k].voxels.words()[w];
      return std::pair{
          std::int64_t(std::popcount(s[w] | v) - std::popcount(s[w])),
          std::int64_t(std::popcount((s[w] | v) & in[w]) - std::popcount(s[w] & in[w]))};
    };
    // The counts of without[i] ∪ extra[k] (i = count: the whole union), from
    // what extra[k] adds to the whole union and, where without[i] differs
    // from it, the difference.
    std::vector<std::pair<std::int64_t, std::int64_t>> toUnion(extra.size());
    const auto countsWith = [&](std::size_t i, std::size_t k) {
      auto [all, kept] = toUnion[k];
      if (i < count) {
        const auto s = without[i].words();
        for (std::uint32_t w : differs[i]) {
          const auto [a0, k0] = added(u, k, w);
          const auto [a1, k1] = added(s, k, w);
          all += a1 - a0;
          kept += k1 - k0;
        }
      }
      return std::pair{std::size_t(std::int64_t(withoutCounts[i].first) + all),
                       std::size_t(std::int64_t(withoutCounts[i].second) + kept)};
    };
    for (std::size_t k = 0; k < extra.size(); ++k) {
      const bool present = std::any_of(members.begin(), members.end(), [&](const UnionMember& m) {
        return m.root == extra[k].root && m.actions == extra[k].actions;
      });
      if (present || VoxelSet::countAnd(extra[k].voxels, inside) == 0) continue;
      toUnion[k] = {0, 0};
      for (std::uint32_t w : extraWords[k]) {
        const auto [a, b] = added(u, k, w);
        toUnion[k].first += a;
        toUnion[k].second += b;
      }
      const std::size_t withK = prims + memberPrimitives(extra[k]);
      const auto [all, kept] = countsWith(count, k);
      const double e = energyOf(withK, all, kept, insideCount, cost);
      MemberRefs trial = refsOf(members);
      trial.push_back(&extra[k]);
      // pruneMembers' first pass: the first member whose removal lowers e.
      std::size_t first = trial.size();
      double firstEnergy = e;
      for (std::size_t i = 0; i < trial.size() && trial.size() > 1; ++i) {
        double ei = 0.0;
        if (i < count) {
          const auto [a, b] = countsWith(i, k);
          ei = energyOf(withK - memberPrimitives(members[i]), a, b, insideCount, cost);
        } else {
          ei = energyOf(prims, withoutCounts[count].first, withoutCounts[count].second, insideCount,
                        cost);
        }
        if (ei < e - 1e-9) {
          first = i;
          firstEnergy = ei;
          break;
        }
      }
      if (first == trial.size()) {
        if (e < energy - 1e-9 && tryMove(trial, e)) return true;
        continue;
      }
      trial.erase(trial.begin() + long(first));
      if (tryMove(trial, firstEnergy)) return true;
    }
    return false;
  };
  for (bool improved = true; improved;) {
    improved = false;
    for (std::size_t i = 0; i < members.size() && !improved; ++i) {
      for (std::size_t a = 0; a < members[i].actions.size() && !improved; ++a) {
        UnionMember m = members[i];
        m.actions.erase(m.actions.begin() + long(a));
        m.voxels = memberVoxels(m, d);
        const MemberRefs trial = replaced(i, m);
        improved = tryMove(trial, energyOf(trial, inside, cost));
      }
    }
    if (!improved) improved = tryExtras();
    if (improved) continue;
    // The best new or replaced action over all members and candidates.
    std::size_t prims = 0;
    for (const UnionMember& m : members) prims += memberPrimitives(m);
    double bestEnergy = energy - 1e-9;
    std::size_t bestUnionMember = 0;
    std::size_t bestSlot = std::size_t(-1);  // -1: a new action, else the action replaced
    SubtreeAction bestAction;
    bool found = false;
    for (std::size_t i = 0; i < members.size(); ++i) {
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
        if (e < bestEnergy) {
          bestEnergy = e;
          bestUnionMember = i;
          bestSlot = slot;
          bestAction = SubtreeAction{k, subtract};
          found = true;
        }
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
    if (found) {
      UnionMember m = members[bestUnionMember];
      if (bestSlot == std::size_t(-1)) {
        m.actions.push_back(bestAction);
      } else {
        m.actions[bestSlot] = bestAction;
      }
      m.voxels = memberVoxels(m, d);
      const MemberRefs trial = replaced(bestUnionMember, m);
      improved = tryMove(trial, energyOf(trial, inside, cost));
    }
  }
}

}  // namespace csgvox
