#include "optimize/csg_construction.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "optimize/union_search.h"
#include "optimize/union_simplification.h"

namespace csgvox {
namespace {

CsgTree memberTree(const UnionMember& m, std::span<const CsgTree> candidates, double snap,
                   const ScannedAt& scannedAt) {
  std::vector<CsgTree> inter{candidates[m.root]};
  std::vector<CsgTree> sub;
  for (const SubtreeAction& a : m.actions) {
    if (a.subtract) {
      sub.push_back(throughCut(candidates[a.primitive], candidates[m.root], snap, scannedAt));
    } else {
      inter.push_back(candidates[a.primitive]);
    }
  }
  CsgTree t = inter.size() == 1 ? inter.front() : CsgTree::intersect(inter);
  if (sub.empty()) return t;
  for (CsgTree& tool : sub) tool = throughSkin(tool, t, snap, scannedAt);
  sub.insert(sub.begin(), t);
  return CsgTree::subtract(sub);
}

}  // namespace

Construction constructCsg(std::span<const CsgTree> candidates, std::span<const DescriptionSet> d,
                          const VoxelSet& inside, const ConstructOptions& options,
                          const ProgressCallback& progress) {
  Construction out;
  const std::size_t n = candidates.size();
  const std::size_t size = inside.size();
  out.stats.candidates = n;
  out.voxels = VoxelSet(size);
  const auto clean = [&](std::size_t outside, std::size_t all) {
    return double(outside) <= options.outsideTolerance * double(all);
  };
  // Roots (Wu §4.1).
  std::vector<std::uint32_t> usable, truncate;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (d[i].plus == 0 || d[i].exceedsGrid) continue;
    (clean(d[i].minus, d[i].voxels.count()) ? usable : truncate).push_back(i);
  }
  std::vector<VoxelSet> usablePlus;
  for (std::uint32_t i : usable) usablePlus.push_back(d[i].voxels & inside);
  std::erase_if(truncate, [&](std::uint32_t i) {
    const VoxelSet plus = d[i].voxels & inside;
    return std::any_of(usablePlus.begin(), usablePlus.end(),
                       [&](const VoxelSet& p) { return p == plus; });
  });
  out.stats.usableRoots = usable.size();
  out.stats.truncationRoots = truncate.size();

  SubtreeOptions subtreeOptions = options.subtree;
  subtreeOptions.seed = options.seed;
  UnionOptions unionOptions = options.unionChoice;
  unionOptions.seed = options.seed;

  // Phase 1: a subtree per truncation root, in parallel.
  std::vector<SubtreeResult> subtrees(truncate.size());
  std::atomic<std::size_t> done{0};
  std::atomic<bool> cancelled{false};
  tbb::parallel_for(std::size_t(0), truncate.size(), [&](std::size_t r) {
    if (cancelled) return;
    const std::uint32_t j = truncate[r];
    std::vector<const VoxelSet*> nb;
    std::vector<std::uint32_t> ids;
    for (std::uint32_t k = 0; k < n; ++k) {
      if (k != j && VoxelSet::intersects(d[k].voxels, d[j].voxels)) {
        nb.push_back(&d[k].voxels);
        ids.push_back(k);
      }
    }
    subtrees[r] = selectSubtree(d[j].voxels, inside, nb, ids, subtreeOptions);
    const std::size_t finished = ++done;
    if (progress && !progress(0.9 * double(finished) / double(truncate.size()), "subtrees")) {
      cancelled = true;
    }
  });

  // Phase 2 candidates: usable primitives and subtrees without outside voxels.
  std::vector<UnionMember> pool;
  for (std::uint32_t i : usable) pool.push_back(UnionMember{i, {}, d[i].voxels});
  for (std::size_t r = 0; r < truncate.size(); ++r) {
    if (!out.stats.provedOptimal || !subtrees[r].provedOptimal) out.stats.provedOptimal = false;
    const VoxelSet& v = subtrees[r].voxels;
    if (v.none() || !clean(VoxelSet::countAndNot(v, inside), v.count())) continue;
    pool.push_back(UnionMember{truncate[r], subtrees[r].actions, v});
    ++out.stats.subtrees;
  }
  out.stats.unionCandidates = pool.size();
  std::vector<const VoxelSet*> sets;
  for (const UnionMember& m : pool) sets.push_back(&m.voxels);
  const UnionResult u = selectUnion(inside, sets, unionOptions);
  if (!u.provedOptimal) out.stats.provedOptimal = false;
  std::vector<UnionMember> members;
  for (std::uint32_t i : u.chosen) members.push_back(pool[i]);
  out.stats.selected = members.size();
  if (progress) progress(0.95, "union");

  if (options.unionSearch) {
    std::vector<UnionMember> extra;
    for (std::uint32_t i = 0; i < n; ++i) {
      if (d[i].plus > 0 && !d[i].exceedsGrid) extra.push_back(UnionMember{i, {}, d[i].voxels});
    }
    for (std::size_t r = 0; r < truncate.size(); ++r) {
      if (!subtrees[r].voxels.none()) {
        extra.push_back(UnionMember{truncate[r], subtrees[r].actions, subtrees[r].voxels});
      }
    }
    searchUnion(members, extra, d, inside, std::max(options.unionChoice.minFeatureVoxels, 1.0));
  }
  if (options.simplify) dropNoOps(members, d, size);
  out.stats.chosen = members.size();
  out.voxels = unionVoxels(members, size);
  if (members.empty()) return out;

  // Subtractions shared by several members are applied once to the union
  // when that leaves the voxels unchanged.
  std::vector<std::uint32_t> lifted;
  if (options.simplify) lifted = liftSharedSubtractions(members, d, size);
  std::vector<CsgTree> parts;
  for (const UnionMember& m : members) {
    parts.push_back(memberTree(m, candidates, options.snapDistance, options.scannedAt));
  }
  CsgTree tree = parts.size() == 1 ? parts.front() : CsgTree::unite(parts);
  if (!lifted.empty()) {
    std::vector<CsgTree> ops{tree};
    for (std::uint32_t l : lifted) {
      ops.push_back(throughSkin(candidates[l], tree, options.snapDistance, options.scannedAt));
    }
    tree = CsgTree::subtract(ops);
  }
  out.tree = tree;
  if (progress) progress(1.0, "union");
  return out;
}

}  // namespace csgvox
