#include "evolve/tree_variation.h"

#include <stdexcept>

namespace csgvox {
namespace {

void collectPaths(const Node& node, NodePath& path, std::vector<NodePath>& out) {
  out.push_back(path);
  for (std::size_t k = 0; k < node.children.size(); ++k) {
    path.push_back(k);
    collectPaths(*node.children[k], path, out);
    path.pop_back();
  }
}

NodeKind randomOperation(EvolveRng& rng) {
  constexpr NodeKind kinds[] = {NodeKind::Union, NodeKind::Intersection, NodeKind::Difference};
  return kinds[uniformIndex(rng, 3)];
}

CsgTree randomLeaf(EvolveRng& rng, const PrimitiveLibrary& library) {
  return library.leafTree(uniformIndex(rng, library.size()));
}

CsgTree withinDepth(CsgTree child, const CsgTree& parent, const VariationOptions& options) {
  return child.depth() <= options.maxDepth ? child : parent;
}

CsgTree regrow(EvolveRng& rng, const CsgTree& tree, const PrimitiveLibrary& library,
               const VariationOptions& options) {
  const std::vector<NodePath> paths = nodePaths(tree);
  const NodePath& at = paths[uniformIndex(rng, paths.size())];
  return tree.replaceSubtree(
      at, randomTree(rng, library, options.mutationDepth, options.operationProbability));
}

// The subtree at a random node becomes one operand of a new operation whose
// other operand is a small random tree.
CsgTree insert(EvolveRng& rng, const CsgTree& tree, const PrimitiveLibrary& library,
               const VariationOptions& options) {
  const std::vector<NodePath> paths = nodePaths(tree);
  const NodePath& at = paths[uniformIndex(rng, paths.size())];
  const CsgTree old(tree.nodeAt(at));
  const CsgTree extra =
      randomTree(rng, library, std::max<std::size_t>(options.mutationDepth / 2, 1),
                 options.operationProbability);
  const bool first = uniformIndex(rng, 2) == 0;
  const NodeKind kind = randomOperation(rng);
  std::vector<NodePtr> operands = first ? std::vector<NodePtr>{old.root(), extra.root()}
                                        : std::vector<NodePtr>{extra.root(), old.root()};
  return tree.replaceSubtree(at, CsgTree(std::make_shared<const Node>(kind, std::move(operands))));
}

// A random operation node replaced by one of its operands.
CsgTree remove(EvolveRng& rng, const CsgTree& tree) {
  std::vector<NodePath> operations;
  for (NodePath& path : nodePaths(tree)) {
    if (tree.nodeAt(path)->kind != NodeKind::Primitive) operations.push_back(std::move(path));
  }
  if (operations.empty()) return tree;
  const NodePath& at = operations[uniformIndex(rng, operations.size())];
  const NodePtr& node = tree.nodeAt(at);
  return tree.replaceSubtree(at, CsgTree(node->children[uniformIndex(rng, node->children.size())]));
}

CsgTree swapPrimitive(EvolveRng& rng, const CsgTree& tree, const PrimitiveLibrary& library) {
  std::vector<NodePath> leaves;
  for (NodePath& path : nodePaths(tree)) {
    if (tree.nodeAt(path)->kind == NodeKind::Primitive) leaves.push_back(std::move(path));
  }
  const NodePath& at = leaves[uniformIndex(rng, leaves.size())];
  return tree.replaceSubtree(at, randomLeaf(rng, library));
}

CsgTree swapOperation(EvolveRng& rng, const CsgTree& tree) {
  std::vector<NodePath> operations;
  for (NodePath& path : nodePaths(tree)) {
    const NodeKind kind = tree.nodeAt(path)->kind;
    if (kind != NodeKind::Primitive && kind != NodeKind::Complement) {
      operations.push_back(std::move(path));
    }
  }
  if (operations.empty()) return tree;
  const NodePath& at = operations[uniformIndex(rng, operations.size())];
  const NodePtr& node = tree.nodeAt(at);
  NodeKind kind = randomOperation(rng);
  while (kind == node->kind) kind = randomOperation(rng);
  return tree.replaceSubtree(at, CsgTree(std::make_shared<const Node>(kind, node->children)));
}

}  // namespace

std::size_t uniformIndex(EvolveRng& rng, std::size_t n) { return std::size_t(rng() % n); }

double uniformUnit(EvolveRng& rng) { return double(rng() >> 11) * 0x1.0p-53; }

std::vector<NodePath> nodePaths(const CsgTree& tree) {
  std::vector<NodePath> out;
  if (tree.empty()) return out;
  NodePath path;
  collectPaths(*tree.root(), path, out);
  return out;
}

CsgTree randomTree(EvolveRng& rng, const PrimitiveLibrary& library, std::size_t depth,
                   double operationProbability) {
  if (library.empty()) throw std::invalid_argument("randomTree: no primitives");
  if (depth <= 1 || library.size() == 1 || uniformUnit(rng) >= operationProbability) {
    return randomLeaf(rng, library);
  }
  const NodeKind kind = randomOperation(rng);
  const CsgTree a = randomTree(rng, library, depth - 1, operationProbability);
  const CsgTree b = randomTree(rng, library, depth - 1, operationProbability);
  return CsgTree(std::make_shared<const Node>(kind, std::vector<NodePtr>{a.root(), b.root()}));
}

std::pair<CsgTree, CsgTree> crossover(EvolveRng& rng, const CsgTree& a, const CsgTree& b,
                                      const VariationOptions& options) {
  const std::vector<NodePath> pa = nodePaths(a), pb = nodePaths(b);
  const NodePath& atA = pa[uniformIndex(rng, pa.size())];
  const NodePath& atB = pb[uniformIndex(rng, pb.size())];
  const CsgTree subA(a.nodeAt(atA)), subB(b.nodeAt(atB));
  return {withinDepth(a.replaceSubtree(atA, subB), a, options),
          withinDepth(b.replaceSubtree(atB, subA), b, options)};
}

CsgTree mutate(EvolveRng& rng, const CsgTree& tree, const PrimitiveLibrary& library,
               const VariationOptions& options) {
  if (uniformUnit(rng) < options.newTreeProbability) {
    return randomTree(rng, library, options.initialDepth, options.operationProbability);
  }
  CsgTree out;
  switch (uniformIndex(rng, 5)) {
    case 0:
      out = regrow(rng, tree, library, options);
      break;
    case 1:
      out = insert(rng, tree, library, options);
      break;
    case 2:
      out = remove(rng, tree);
      break;
    case 3:
      out = swapPrimitive(rng, tree, library);
      break;
    default:
      out = swapOperation(rng, tree);
      break;
  }
  return withinDepth(std::move(out), tree, options);
}

}  // namespace csgvox
