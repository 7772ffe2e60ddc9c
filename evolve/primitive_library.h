#pragma once
/// The primitives a genetic search combines. Each primitive has one leaf node
/// that every tree of the search shares, so a tree's leaves map back to the
/// library by address, and crossover and mutation never copy a primitive.

#include <cstddef>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/csg_tree.h"

namespace csgvox {

/// A fixed, indexed set of primitives with their shared leaf nodes.
class PrimitiveLibrary {
 public:
  PrimitiveLibrary() = default;
  /// One leaf per primitive, named by `names` (same size as `primitives`).
  /// @throw std::invalid_argument when the sizes differ, a primitive is
  ///        invalid, or there are more than 32767 primitives.
  PrimitiveLibrary(std::vector<Primitive> primitives, std::vector<std::string> names);

  /// The library of a tree's own leaves (equal primitives once, in
  /// depth-first order, with their names).
  static PrimitiveLibrary ofTree(const CsgTree& tree);

  std::size_t size() const { return leaves_.size(); }
  bool empty() const { return leaves_.empty(); }
  const Primitive& primitive(std::size_t i) const { return leaves_[i]->primitive; }
  const std::string& name(std::size_t i) const { return leaves_[i]->name; }
  /// The shared leaf node of primitive i.
  const NodePtr& leaf(std::size_t i) const { return leaves_[i]; }
  /// The one-leaf tree of primitive i.
  CsgTree leafTree(std::size_t i) const { return CsgTree(leaves_[i]); }

  /// The index of a leaf node: by address for the library's own leaves, else
  /// the first primitive equal to the leaf's (Primitive::operator==).
  std::optional<std::size_t> indexOf(const Node& leaf) const;
  /// The same tree with every leaf replaced by the library's own leaf node.
  /// @throw std::invalid_argument naming the first leaf whose primitive is not
  ///        in the library.
  CsgTree adopt(const CsgTree& tree) const;

 private:
  std::vector<NodePtr> leaves_;
  std::unordered_map<const Node*, std::size_t> index_;
};

}  // namespace csgvox
