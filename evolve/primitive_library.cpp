#include "evolve/primitive_library.h"

#include <stdexcept>

namespace csgvox {

PrimitiveLibrary::PrimitiveLibrary(std::vector<Primitive> primitives,
                                   std::vector<std::string> names) {
  if (primitives.size() != names.size()) {
    throw std::invalid_argument("PrimitiveLibrary: " + std::to_string(primitives.size()) +
                                " primitives but " + std::to_string(names.size()) + " names");
  }
  if (primitives.size() > 32767) {
    throw std::invalid_argument("PrimitiveLibrary: more than 32767 primitives");
  }
  leaves_.reserve(primitives.size());
  for (std::size_t i = 0; i < primitives.size(); ++i) {
    primitives[i].validate();
    leaves_.push_back(std::make_shared<const Node>(primitives[i], std::move(names[i])));
    index_.emplace(leaves_.back().get(), i);
  }
}

std::optional<std::size_t> PrimitiveLibrary::indexOf(const Node& leaf) const {
  if (const auto it = index_.find(&leaf); it != index_.end()) return it->second;
  if (leaf.kind != NodeKind::Primitive) return std::nullopt;
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    if (leaves_[i]->primitive == leaf.primitive) return i;
  }
  return std::nullopt;
}

PrimitiveLibrary PrimitiveLibrary::ofTree(const CsgTree& tree) {
  std::vector<Primitive> primitives;
  std::vector<std::string> names;
  for (const Node* leaf : tree.leaves()) {
    bool known = false;
    for (const Primitive& p : primitives) known = known || p == leaf->primitive;
    if (known) continue;
    primitives.push_back(leaf->primitive);
    names.push_back(leaf->name);
  }
  return PrimitiveLibrary(std::move(primitives), std::move(names));
}

namespace {

NodePtr adoptNode(const PrimitiveLibrary& library, const NodePtr& node) {
  if (node->kind == NodeKind::Primitive) {
    const std::optional<std::size_t> i = library.indexOf(*node);
    if (!i) {
      throw std::invalid_argument("leaf '" + node->name + "' (" +
                                  std::string(primitiveTypeName(node->primitive.type())) +
                                  ") is not one of the search's primitives");
    }
    return library.leaf(*i);
  }
  std::vector<NodePtr> children;
  children.reserve(node->children.size());
  for (const NodePtr& c : node->children) children.push_back(adoptNode(library, c));
  return std::make_shared<const Node>(node->kind, std::move(children));
}

}  // namespace

CsgTree PrimitiveLibrary::adopt(const CsgTree& tree) const {
  if (tree.empty()) return tree;
  return CsgTree(adoptNode(*this, tree.root()));
}

}  // namespace csgvox
