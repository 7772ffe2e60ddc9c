#include "evolve/partition.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <unordered_map>
#include <stdexcept>

#include "evolve/tree_variation.h"

namespace csgvox {

Graph overlapGraph(std::span<const Aabb> hulls) {
  Graph graph(hulls.size());
  for (std::size_t i = 0; i < hulls.size(); ++i) {
    if (hulls[i].isEmpty()) continue;
    for (std::size_t j = i + 1; j < hulls.size(); ++j) {
      if (hulls[j].isEmpty() || hulls[i].intersected(hulls[j]).isEmpty()) continue;
      graph[i].push_back(j);
      graph[j].push_back(i);
    }
  }
  for (auto& adjacent : graph) std::sort(adjacent.begin(), adjacent.end());
  return graph;
}

namespace {

using Set = std::vector<std::size_t>;  // sorted vertex set

Set intersection(const Set& a, const Set& b) {
  Set out;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

// Bron–Kerbosch with Tomita's pivot: the pivot is the vertex of P ∪ X with
// the most neighbours in P, and only the vertices of P it does not neighbour
// are branched on.
void bronKerbosch(const Graph& graph, Set& clique, Set candidates, Set excluded,
                  std::vector<Set>& out) {
  if (candidates.empty()) {
    if (excluded.empty()) out.push_back(clique);
    return;
  }
  std::size_t pivot = candidates.front(), best = 0;
  for (const Set* s : {&candidates, &excluded}) {
    for (const std::size_t u : *s) {
      const std::size_t n = intersection(graph[u], candidates).size();
      if (n > best || (n == best && u < pivot && s == &candidates)) pivot = u, best = n;
    }
  }
  Set branch;
  std::set_difference(candidates.begin(), candidates.end(), graph[pivot].begin(),
                      graph[pivot].end(), std::back_inserter(branch));
  for (const std::size_t v : branch) {
    clique.insert(std::upper_bound(clique.begin(), clique.end(), v), v);
    bronKerbosch(graph, clique, intersection(candidates, graph[v]),
                 intersection(excluded, graph[v]), out);
    clique.erase(std::find(clique.begin(), clique.end(), v));
    candidates.erase(std::find(candidates.begin(), candidates.end(), v));
    excluded.insert(std::upper_bound(excluded.begin(), excluded.end(), v), v);
  }
}

}  // namespace

std::vector<std::vector<std::size_t>> maximalCliques(const Graph& graph) {
  Set all(graph.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  std::vector<Set> out;
  Set clique;
  bronKerbosch(graph, clique, all, {}, out);
  std::sort(out.begin(), out.end());
  return out;
}

PrimitiveSupport primitiveSupport(std::span<const Vec3> points, const PrimitiveLibrary& library,
                                  double tolerance) {
  if (library.empty()) throw std::invalid_argument("partitioning needs at least one primitive");
  PrimitiveSupport out;
  out.hulls.assign(library.size(), Aabb{});
  out.nearest.assign(points.size(), 0);
  std::vector<double> distance(points.size(), std::numeric_limits<double>::infinity());
  for (std::size_t p = 0; p < library.size(); ++p) {
    const Primitive& primitive = library.primitive(p);
    std::vector<double> values(points.size());
    tbb::parallel_for(std::size_t{0}, points.size(),
                      [&](std::size_t i) { values[i] = std::abs(primitive.value(points[i])); });
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (values[i] < distance[i]) distance[i] = values[i], out.nearest[i] = std::uint32_t(p);
    }
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (distance[i] <= tolerance) out.hulls[out.nearest[i]].extend(points[i]);
  }
  return out;
}

std::vector<SearchPartition> partitionSearch(const PrimitiveSupport& support, double margin) {
  std::vector<Aabb> hulls;
  for (const Aabb& box : support.hulls) hulls.push_back(box.grown(margin));
  std::vector<SearchPartition> out;
  for (const Set& clique : maximalCliques(overlapGraph(hulls))) {
    if (clique.size() == 1 && hulls[clique.front()].isEmpty()) continue;
    SearchPartition partition{clique, {}};
    for (std::size_t i = 0; i < support.nearest.size(); ++i) {
      if (std::binary_search(clique.begin(), clique.end(), std::size_t(support.nearest[i]))) {
        partition.points.push_back(std::uint32_t(i));
      }
    }
    if (!partition.points.empty()) out.push_back(std::move(partition));
  }
  return out;
}

namespace {

// Paths of the valid merge nodes of a tree (Algorithm 1): the root, and the
// operands of every union node reached that way.
void mergeNodes(const NodePtr& node, NodePath& path, std::vector<NodePath>& out) {
  out.push_back(path);
  if (node->kind != NodeKind::Union) return;
  for (std::size_t c = 0; c < node->children.size(); ++c) {
    path.push_back(c);
    mergeNodes(node->children[c], path, out);
    path.pop_back();
  }
}

// The subtrees of a tree by structural hash.
std::unordered_multimap<std::size_t, NodePtr> subtreeIndex(const CsgTree& tree) {
  std::unordered_multimap<std::size_t, NodePtr> out;
  for (const NodePath& path : nodePaths(tree)) {
    const NodePtr& node = tree.nodeAt(path);
    out.emplace(CsgTree(node).structuralHash(), node);
  }
  return out;
}

// Whether a subtree of the indexed tree has the structure of `sub`.
bool occurs(const CsgTree& sub, const std::unordered_multimap<std::size_t, NodePtr>& index) {
  const auto [first, last] = index.equal_range(sub.structuralHash());
  return std::any_of(first, last,
                     [&](const auto& entry) { return CsgTree(entry.second).structurallyEqual(sub); });
}

// Joins two trees at their largest common subtree that is a valid merge node
// in one of them (the larger tree's node on a tie); an empty tree when there
// is none.
CsgTree mergePair(const CsgTree& t0, const CsgTree& t1) {
  const bool firstLarger = t0.nodeCount() >= t1.nodeCount();
  const CsgTree& large = firstLarger ? t0 : t1;
  const CsgTree& small = firstLarger ? t1 : t0;
  const auto largeIndex = subtreeIndex(large), smallIndex = subtreeIndex(small);
  const CsgTree* target = nullptr;  // the tree whose node is replaced
  NodePath at;
  std::size_t bestNodes = 0;
  const auto consider = [&](const CsgTree& tree, const auto& otherIndex) {
    std::vector<NodePath> valid;
    NodePath path;
    mergeNodes(tree.root(), path, valid);
    for (const NodePath& p : valid) {
      const CsgTree sub(tree.nodeAt(p));
      if (sub.nodeCount() > bestNodes && occurs(sub, otherIndex)) {
        target = &tree;
        at = p;
        bestNodes = sub.nodeCount();
      }
    }
  };
  consider(large, smallIndex);
  consider(small, largeIndex);
  if (!target) return {};
  return target->replaceSubtree(at, target == &large ? small : large);
}

}  // namespace

CsgTree mergePartitionTrees(std::vector<CsgTree> trees) {
  if (trees.empty()) throw std::invalid_argument("no trees to merge");
  for (const CsgTree& t : trees) {
    if (t.empty()) throw std::invalid_argument("an empty tree among the trees to merge");
  }
  std::size_t stuck = 0;  // consecutive trees t0 that joined none of the others
  while (trees.size() > 1) {
    CsgTree t0 = std::move(trees[trees.size() - 2]);
    trees.erase(trees.end() - 2);
    bool merged = false;
    for (std::size_t tried = 0; tried < trees.size() && !merged; ++tried) {
      CsgTree t1 = std::move(trees.back());
      trees.pop_back();
      CsgTree joined = mergePair(t0, t1);
      if (joined.empty()) {
        trees.insert(trees.begin(), std::move(t1));
      } else {
        trees.push_back(std::move(joined));
        merged = true;
      }
    }
    if (merged) {
      stuck = 0;
      continue;
    }
    trees.insert(trees.begin(), std::move(t0));
    if (++stuck >= trees.size()) return CsgTree::unite(trees);
  }
  return trees.front();
}

}  // namespace csgvox
