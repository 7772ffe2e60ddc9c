#pragma once
/// The variation operators of the genetic search over CSG trees: random
/// trees, subtree crossover, and the mutations of Fayolle & Pasko 2016 (a
/// new tree, a regrown subtree) and of SURREAL (insertion, deletion,
/// primitive swap), plus an operation swap. Every operator returns a new tree
/// sharing the unchanged subtrees with its parents; leaves are always the
/// library's own leaf nodes. Operators draw from the given generator only, so
/// a seed fixes their results.

#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "core/csg_tree.h"
#include "evolve/primitive_library.h"

namespace csgvox {

/// The generator of the genetic search.
using EvolveRng = std::mt19937_64;

/// Options of the variation operators.
struct VariationOptions {
  double operationProbability = 0.7;  ///< a random node is an operation (else a leaf) with this
  std::size_t initialDepth = 4;       ///< depth bound of random initial trees (levels)
  std::size_t mutationDepth = 4;      ///< depth bound of regrown and inserted subtrees (levels)
  std::size_t maxDepth = 10;          ///< offspring deeper than this are rejected (levels)
  double newTreeProbability = 0.1;    ///< a mutation replaces the whole tree with this
};

/// Every node's path in depth-first pre-order (the root's path first).
std::vector<NodePath> nodePaths(const CsgTree& tree);

/// A random tree of depth <= `depth` over the library (binary union,
/// intersection and difference, equally likely).
/// @throw std::invalid_argument when the library is empty.
CsgTree randomTree(EvolveRng& rng, const PrimitiveLibrary& library, std::size_t depth,
                   double operationProbability);

/// Subtree crossover: a random subtree of each parent swapped. A child deeper
/// than options.maxDepth is replaced by its parent.
std::pair<CsgTree, CsgTree> crossover(EvolveRng& rng, const CsgTree& a, const CsgTree& b,
                                      const VariationOptions& options);

/// One random mutation: a new random tree (newTreeProbability), else, equally
/// likely, a random subtree regrown, a random subtree inserted as an operand
/// beside a node, an operation node replaced by one of its operands, a leaf
/// swapped for another primitive, or an operation swapped for another. A
/// result deeper than options.maxDepth is replaced by the parent.
CsgTree mutate(EvolveRng& rng, const CsgTree& tree, const PrimitiveLibrary& library,
               const VariationOptions& options);

/// Uniform integer in [0, n) (n > 0), the same on every standard library.
std::size_t uniformIndex(EvolveRng& rng, std::size_t n);
/// Uniform real in [0, 1), the same on every standard library.
double uniformUnit(EvolveRng& rng);

}  // namespace csgvox
