#pragma once
/// Friedrich et al. 2018's search-space partitioning, the geometric half:
/// the primitive-overlap graph (an edge between two primitives whose hulls
/// overlap), its maximal cliques (Bron–Kerbosch with pivoting), each one the
/// primitive set of an independent search, and the merge of the per-partition
/// trees through their largest common subtrees (§5.4, Algorithm 1).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/csg_tree.h"
#include "core/geometry.h"
#include "evolve/primitive_library.h"

namespace csgvox {

/// Adjacency lists of an undirected graph over vertices 0..n-1 (each list
/// sorted, no self-loops).
using Graph = std::vector<std::vector<std::size_t>>;

/// The overlap graph of boxes: an edge between i and j (i ≠ j) when both are
/// non-empty and they intersect (touching counts).
Graph overlapGraph(std::span<const Aabb> hulls);

/// Every maximal clique of the graph (Bron–Kerbosch with Tomita's pivot),
/// each sorted, the list sorted lexicographically. An isolated vertex is a
/// clique of its own.
std::vector<std::vector<std::size_t>> maximalCliques(const Graph& graph);

/// The points each primitive of a library explains: for every primitive, the
/// box of the points within `tolerance` of its surface (|f| ≤ tolerance;
/// empty when there are none) — the primitive's hull in the overlap graph —
/// and for every point the primitive whose surface is nearest (smallest |f|).
struct PrimitiveSupport {
  std::vector<Aabb> hulls;             ///< per primitive
  std::vector<std::uint32_t> nearest;  ///< per point, a library index
};

/// Computes the supports of a library's primitives on points.
/// @throw std::invalid_argument when the library is empty.
PrimitiveSupport primitiveSupport(std::span<const Vec3> points, const PrimitiveLibrary& library,
                                  double tolerance);

/// One partition of a search: its primitives and the points whose nearest
/// primitive is one of them.
struct SearchPartition {
  std::vector<std::size_t> primitives;  ///< library indices, sorted
  std::vector<std::uint32_t> points;    ///< point indices, ascending
};

/// The partitions of a search: the maximal cliques of the overlap graph of
/// the support hulls, each grown by `margin` on every side; primitives
/// without support and cliques without points are left out.
std::vector<SearchPartition> partitionSearch(const PrimitiveSupport& support, double margin);

/// Merges per-partition trees into one (Friedrich §5.4): the second-to-last
/// tree t0 of the list is joined with the last one t1 at their largest common
/// subtree that is a valid merge node (reached from a root through unions
/// only, Algorithm 1) — that node of the larger tree replaced by the smaller
/// tree's root (t0's node on a tie) — and the result goes to the end of the
/// list. When t0 and t1 have no such subtree, t1 goes to the front and t0 is
/// tried with the next tree from the end; a t0 that joins none goes to the
/// front. When no pair of the remaining trees can be joined, they are united.
/// Trees are compared by structure (CsgTree::structurallyEqual).
/// @throw std::invalid_argument when `trees` is empty or holds an empty tree.
CsgTree mergePartitionTrees(std::vector<CsgTree> trees);

}  // namespace csgvox
