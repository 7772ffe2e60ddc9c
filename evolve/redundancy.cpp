#include "evolve/redundancy.h"

#include "evolve/tree_variation.h"

namespace csgvox {
namespace {

NodePtr normalizeNode(const NodePtr& node) {
  if (node->kind == NodeKind::Primitive) return node;
  if (node->kind == NodeKind::Complement) {
    const NodePtr inner = normalizeNode(node->children.front());
    if (inner->kind == NodeKind::Complement) return inner->children.front();
    if (inner == node->children.front()) return node;
    return std::make_shared<const Node>(NodeKind::Complement, std::vector<NodePtr>{inner});
  }
  std::vector<NodePtr> children;
  children.reserve(node->children.size());
  bool changed = false;
  for (const NodePtr& c : node->children) {
    children.push_back(normalizeNode(c));
    changed = changed || children.back() != c;
  }
  if (children.size() == 1) return children.front();
  if (!changed) return node;
  return std::make_shared<const Node>(node->kind, std::move(children));
}

// The variants of the tree with the operation at `path` simplified: replaced
// by each operand, or (n-ary) without one operand.
std::vector<CsgTree> simplerVariants(const CsgTree& tree, const NodePath& path) {
  std::vector<CsgTree> out;
  const NodePtr& node = tree.nodeAt(path);
  if (node->kind == NodeKind::Primitive || node->kind == NodeKind::Complement) return out;
  for (const NodePtr& child : node->children)
    out.push_back(tree.replaceSubtree(path, CsgTree(child)));
  if (node->children.size() > 2) {
    for (std::size_t k = 0; k < node->children.size(); ++k) {
      // The first operand of a difference is what the others are cut from.
      if (node->kind == NodeKind::Difference && k == 0) continue;
      std::vector<NodePtr> rest = node->children;
      rest.erase(rest.begin() + std::ptrdiff_t(k));
      out.push_back(tree.replaceSubtree(
          path, CsgTree(std::make_shared<const Node>(node->kind, std::move(rest)))));
    }
  }
  return out;
}

}  // namespace

CsgTree normalizeTree(const CsgTree& tree) {
  if (tree.empty()) return tree;
  return CsgTree(normalizeNode(tree.root()));
}

CsgTree removeRedundancy(const CsgTree& tree, const FitnessModel& model) {
  CsgTree current = normalizeTree(tree);
  double best = model.evaluate(current).total;
  // The normalised tree is the same solid with fewer nodes: never worse.
  bool improved = true;
  while (improved) {
    improved = false;
    for (const NodePath& path : nodePaths(current)) {
      for (CsgTree& variant : simplerVariants(current, path)) {
        variant = normalizeTree(variant);
        const double f = model.evaluate(variant).total;
        if (f >= best) {
          current = std::move(variant);
          best = f;
          improved = true;
          break;
        }
      }
      if (improved) break;
    }
  }
  return current;
}

}  // namespace csgvox
