#include "evolve/redundancy.h"

#include <algorithm>

#include "evolve/tree_variation.h"

namespace csgvox {
namespace {

bool sameSubtree(const NodePtr& a, const NodePtr& b) {
  return a == b || CsgTree(a).structurallyEqual(CsgTree(b));
}

bool isComplementOf(const NodePtr& a, const NodePtr& b) {
  return a->kind == NodeKind::Complement && sameSubtree(a->children.front(), b);
}

// The node with double complements, single-operand operations, repeated
// operands and operands that cancel (X − X, X ∩ ¬X) removed; nullptr for an
// empty solid.
NodePtr normalizeNode(const NodePtr& node) {
  if (node->kind == NodeKind::Primitive) return node;
  if (node->kind == NodeKind::Complement) {
    const NodePtr inner = normalizeNode(node->children.front());
    if (!inner) return node;  // everything: left as it was
    if (inner->kind == NodeKind::Complement) return inner->children.front();
    if (inner == node->children.front()) return node;
    return std::make_shared<const Node>(NodeKind::Complement, std::vector<NodePtr>{inner});
  }
  std::vector<NodePtr> children;
  children.reserve(node->children.size());
  bool changed = false;
  for (std::size_t k = 0; k < node->children.size(); ++k) {
    const NodePtr& c = node->children[k];
    NodePtr n = normalizeNode(c);
    changed = changed || n != c;
    if (!n) {
      // An empty operand empties an intersection and a difference's first
      // operand; elsewhere it is dropped.
      if (node->kind == NodeKind::Intersection) return nullptr;
      if (node->kind == NodeKind::Difference && k == 0) return nullptr;
      continue;
    }
    // A difference's cutters are compared among themselves and with what
    // they cut; the operands of a union or an intersection with each other.
    const bool cut = node->kind == NodeKind::Difference;
    const auto same = [&](const NodePtr& other) { return sameSubtree(other, n); };
    if (std::any_of(children.begin() + std::ptrdiff_t(cut && !children.empty()), children.end(),
                    same)) {
      changed = true;  // repeated
      continue;
    }
    if (cut && k > 0 && same(children.front())) return nullptr;  // X − X
    if (node->kind == NodeKind::Intersection) {
      for (const NodePtr& other : children)
        if (isComplementOf(other, n) || isComplementOf(n, other)) return nullptr;
    }
    children.push_back(std::move(n));
  }
  if (children.empty()) return nullptr;
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
  const NodePtr root = normalizeNode(tree.root());
  return root ? CsgTree(root) : tree;
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
