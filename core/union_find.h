#pragma once
/// Disjoint sets kept as a forest in a parent array (parent[r] == r at a
/// root): the sets of connected facets, cells or classes.

#include <cstddef>
#include <vector>

namespace csgvox {

/// The root of `i` in the forest `parent`, halving the path on the way.
template <class Index>
Index findRoot(std::vector<Index>& parent, Index i) {
  while (parent[std::size_t(i)] != i) {
    parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
    i = parent[std::size_t(i)];
  }
  return i;
}

}  // namespace csgvox
