#include "core/csg_tree.h"

#include <algorithm>
#include <array>
#include <functional>
#include <stdexcept>
#include <unordered_set>

#include "core/halfspace_bounds.h"
#include "core/tree_program.h"

namespace csgvox {
namespace {

const LeafData& noLeaf() {
  static const LeafData none;
  return none;
}

NodePtr makeOperation(NodeKind kind, const std::vector<CsgTree>& operands) {
  if (operands.empty()) throw std::invalid_argument("an operation needs at least one operand");
  std::vector<NodePtr> children;
  for (const CsgTree& t : operands) {
    if (t.empty()) throw std::invalid_argument("an operand is an empty tree");
    children.push_back(t.root());
  }
  return std::make_shared<Node>(kind, std::move(children));
}

template <class Fn>
void visit(const NodePtr& node, Fn&& fn) {
  if (!node) return;
  fn(*node);
  for (const NodePtr& c : node->children) visit(c, fn);
}

FieldValue evaluateNode(const Node& node, const Vec3& p, const SetOperations& ops) {
  switch (node.kind) {
    case NodeKind::Primitive: {
      FieldValue v;
      v.f = node.primitive.valueAndGradient(p, v.gradient);
      return v;
    }
    case NodeKind::Complement: {
      FieldValue v = evaluateNode(*node.children.front(), p, ops);
      v.f = -v.f;
      v.gradient = -v.gradient;
      return v;
    }
    case NodeKind::Union:
    case NodeKind::Intersection:
    case NodeKind::Difference: {
      FieldValue acc = evaluateNode(*node.children.front(), p, ops);
      for (std::size_t i = 1; i < node.children.size(); ++i) {
        FieldValue v = evaluateNode(*node.children[i], p, ops);
        if (node.kind == NodeKind::Union) {
          acc = ops.unite(acc, v);
        } else if (node.kind == NodeKind::Intersection) {
          acc = ops.intersect(acc, v);
        } else {
          v.f = -v.f;
          v.gradient = -v.gradient;
          acc = ops.intersect(acc, v);
        }
      }
      return acc;
    }
  }
  return {};
}

// Value only, with the set operations chosen at compile time (MinMaxValues,
// RFunctionValues, SardfValues); the same arithmetic and order as evaluateNode.
template <class Ops>
double valueOf(const Node& node, const Vec3& p, const Ops& ops) {
  switch (node.kind) {
    case NodeKind::Primitive:
      return node.primitive.value(p);
    case NodeKind::Complement:
      return -valueOf(*node.children.front(), p, ops);
    case NodeKind::Union: {
      double acc = valueOf(*node.children.front(), p, ops);
      for (std::size_t i = 1; i < node.children.size(); ++i) {
        acc = ops.unite(acc, valueOf(*node.children[i], p, ops));
      }
      return acc;
    }
    case NodeKind::Intersection: {
      double acc = valueOf(*node.children.front(), p, ops);
      for (std::size_t i = 1; i < node.children.size(); ++i) {
        acc = ops.intersect(acc, valueOf(*node.children[i], p, ops));
      }
      return acc;
    }
    case NodeKind::Difference: {
      double acc = valueOf(*node.children.front(), p, ops);
      for (std::size_t i = 1; i < node.children.size(); ++i) {
        acc = ops.intersect(acc, -valueOf(*node.children[i], p, ops));
      }
      return acc;
    }
  }
  return 0.0;
}

std::size_t mixHash(std::size_t h, std::size_t v) {
  return (h ^ (v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2))) * 0x100000001b3ull;
}

std::size_t hashOf(const Node& node) {
  std::size_t h = mixHash(static_cast<std::size_t>(node.kind) + 1, node.children.size());
  if (node.kind == NodeKind::Primitive) return mixHash(h, node.primitive.hash());
  for (const NodePtr& c : node.children) h = mixHash(h, hashOf(*c));
  return h;
}

// Copy of `node` with every occurrence of `target` replaced; nullptr when
// `target` does not occur below it (the caller then keeps `node`).
NodePtr replaced(const NodePtr& node, const Node* target, const NodePtr& replacement) {
  if (node.get() == target) return replacement;
  std::vector<NodePtr> children = node->children;
  bool changed = false;
  for (NodePtr& c : children) {
    if (NodePtr r = replaced(c, target, replacement)) {
      c = std::move(r);
      changed = true;
    }
  }
  if (!changed) return nullptr;
  return std::make_shared<Node>(node->kind, std::move(children));
}

void collectIntersected(const Node& node, Aabb& box, std::vector<HalfSpace>& halfSpaces);

Aabb boundsOf(const Node& node) {
  switch (node.kind) {
    case NodeKind::Primitive:
      return node.primitive.bounds();
    case NodeKind::Complement:
      return Aabb::everything();
    case NodeKind::Union: {
      Aabb b;
      for (const NodePtr& c : node.children) b.extend(boundsOf(*c));
      return b;
    }
    case NodeKind::Difference:
    case NodeKind::Intersection: {
      // Half-spaces anywhere in a chain of intersections (and subtracted
      // ones) bound the solid together, which no one of them does alone.
      Aabb b = Aabb::everything();
      std::vector<HalfSpace> halfSpaces;
      collectIntersected(node, b, halfSpaces);
      return halfSpaceIntersectionBounds(halfSpaces, b);
    }
  }
  return {};
}

// The operands of an intersection, through nested intersections and the
// subtracted operands of differences: half-spaces (a subtracted or
// complemented half-space is the opposite half-space) into `halfSpaces`, the
// bounds of everything else intersected into `box`.
void collectIntersected(const Node& node, Aabb& box, std::vector<HalfSpace>& halfSpaces) {
  const auto add = [&](const Node& operand, bool flipped) {
    const Node* leaf = &operand;
    if (operand.kind == NodeKind::Complement) {
      leaf = operand.children.front().get();
      flipped = !flipped;
    }
    if (leaf->kind == NodeKind::Primitive) {
      if (const HalfSpace* h = leaf->primitive.as<HalfSpace>()) {
        halfSpaces.push_back(flipped ? HalfSpace{-h->normal, -h->offset} : *h);
        return;
      }
    }
    if (flipped) return;  // the complement of anything else bounds nothing
    if (operand.kind == NodeKind::Intersection || operand.kind == NodeKind::Difference) {
      collectIntersected(operand, box, halfSpaces);
    } else {
      box = box.intersected(boundsOf(operand));
    }
  };
  if (node.kind == NodeKind::Difference) {
    add(*node.children.front(), false);
    for (std::size_t k = 1; k < node.children.size(); ++k) add(*node.children[k], true);
    return;
  }
  for (const NodePtr& c : node.children) add(*c, false);
}

std::size_t depthOf(const Node& node) {
  std::size_t d = 0;
  for (const NodePtr& c : node.children) d = std::max(d, depthOf(*c));
  return d + 1;
}

bool equalNodes(const Node& a, const Node& b, double tol) {
  if (a.kind != b.kind || a.children.size() != b.children.size()) return false;
  if (a.kind == NodeKind::Primitive) return a.primitive.approxEqual(b.primitive, tol);
  for (std::size_t i = 0; i < a.children.size(); ++i) {
    if (!equalNodes(*a.children[i], *b.children[i], tol)) return false;
  }
  return true;
}

void validateNode(const Node& node) {
  switch (node.kind) {
    case NodeKind::Primitive:
      if (!node.children.empty()) throw std::invalid_argument("a primitive node has children");
      node.primitive.validate();
      return;
    case NodeKind::Complement:
      if (node.children.size() != 1) {
        throw std::invalid_argument("a complement needs exactly one operand");
      }
      break;
    default:
      if (node.children.empty()) {
        throw std::invalid_argument(std::string(nodeKindName(node.kind)) +
                                    " needs at least one operand");
      }
  }
  for (const NodePtr& c : node.children) {
    if (!c) throw std::invalid_argument("a node has a null child");
    validateNode(*c);
  }
}

}  // namespace

Node::Node(Primitive leafPrimitive, std::string leafName)
    : kind(NodeKind::Primitive),
      leaf_(std::make_unique<const LeafData>(
          LeafData{std::move(leafPrimitive), std::move(leafName)})),
      primitive(leaf_->primitive),
      name(leaf_->name) {}

Node::Node(NodeKind operation, std::vector<NodePtr> operands)
    : kind(operation),
      children(std::move(operands)),
      primitive(noLeaf().primitive),
      name(noLeaf().name) {
  if (operation == NodeKind::Primitive) {
    throw std::invalid_argument("an operation node needs an operation kind");
  }
}

CsgTree CsgTree::leaf(Primitive primitive, std::string name) {
  return CsgTree(std::make_shared<Node>(std::move(primitive), std::move(name)));
}

CsgTree CsgTree::unite(const std::vector<CsgTree>& operands) {
  return CsgTree(makeOperation(NodeKind::Union, operands));
}

CsgTree CsgTree::intersect(const std::vector<CsgTree>& operands) {
  return CsgTree(makeOperation(NodeKind::Intersection, operands));
}

CsgTree CsgTree::subtract(const std::vector<CsgTree>& operands) {
  return CsgTree(makeOperation(NodeKind::Difference, operands));
}

CsgTree CsgTree::complement(const CsgTree& operand) {
  return CsgTree(makeOperation(NodeKind::Complement, {operand}));
}

std::size_t CsgTree::nodeCount() const {
  std::size_t n = 0;
  visit(root_, [&](const Node&) { ++n; });
  return n;
}

std::size_t CsgTree::operationCount() const { return nodeCount() - primitiveCount(); }

std::size_t CsgTree::primitiveCount() const {
  std::size_t n = 0;
  visit(root_, [&](const Node& node) { n += node.kind == NodeKind::Primitive; });
  return n;
}

std::size_t CsgTree::depth() const { return root_ ? depthOf(*root_) : 0; }

std::vector<const Node*> CsgTree::leaves() const {
  std::vector<const Node*> out;
  visit(root_, [&](const Node& node) {
    if (node.kind == NodeKind::Primitive) out.push_back(&node);
  });
  return out;
}

std::vector<const Node*> CsgTree::distinctLeaves() const {
  std::vector<const Node*> out;
  std::unordered_set<const Node*> seen;
  for (const Node* leaf : leaves()) {
    if (seen.insert(leaf).second) out.push_back(leaf);
  }
  return out;
}

double CsgTree::value(const Vec3& p, const SetOperations& ops) const {
  if (!root_) return -std::numeric_limits<double>::infinity();
  switch (ops.kind()) {
    case SetOperationKind::MinMax:
      return valueOf(*root_, p, MinMaxValues{});
    case SetOperationKind::RFunction:
      return valueOf(*root_, p, RFunctionValues{});
    case SetOperationKind::Sardf:
      if (const auto* sardf = dynamic_cast<const SardfOperations*>(&ops)) {
        return valueOf(*root_, p, sardf->values());
      }
      break;
  }
  return evaluate(p, ops).f;
}

void CsgTree::values(std::span<const Vec3> points, std::span<double> out,
                     SetOperationKind ops) const {
  TreeProgram(*this).values(points, out, ops);
}

void CsgTree::values(std::span<const Vec3> points, std::span<double> out,
                     const SetOperations& ops) const {
  TreeProgram(*this).values(points, out, ops);
}

FieldValue CsgTree::evaluate(const Vec3& p, const SetOperations& ops) const {
  if (!root_) {
    FieldValue v;
    v.f = -std::numeric_limits<double>::infinity();
    return v;
  }
  return evaluateNode(*root_, p, ops);
}

Aabb CsgTree::bounds() const { return root_ ? boundsOf(*root_) : Aabb(); }

void CsgTree::validate() const {
  if (!root_) throw std::invalid_argument("the tree is empty");
  validateNode(*root_);
}

bool CsgTree::structurallyEqual(const CsgTree& other, double tolerance) const {
  if (!root_ || !other.root_) return !root_ && !other.root_;
  return equalNodes(*root_, *other.root_, tolerance);
}

std::size_t CsgTree::structuralHash() const { return root_ ? hashOf(*root_) : 0; }

const NodePtr& CsgTree::nodeAt(const NodePath& path) const {
  if (!root_) throw std::out_of_range("nodeAt: the tree is empty");
  const NodePtr* node = &root_;
  for (std::size_t i : path) {
    if (i >= (*node)->children.size()) throw std::out_of_range("nodeAt: the path leaves the tree");
    node = &(*node)->children[i];
  }
  return *node;
}

CsgTree CsgTree::replaceSubtree(const NodePath& path, const CsgTree& replacement) const {
  if (replacement.empty()) throw std::invalid_argument("replaceSubtree: the replacement is empty");
  nodeAt(path);  // checks the path
  // Rebuild the operation nodes along the path, bottom up.
  NodePtr built = replacement.root();
  for (std::size_t level = path.size(); level-- > 0;) {
    const NodePtr& parent = nodeAt(NodePath(path.begin(), path.begin() + level));
    std::vector<NodePtr> children = parent->children;
    children[path[level]] = built;
    built = std::make_shared<Node>(parent->kind, std::move(children));
  }
  return CsgTree(std::move(built));
}

CsgTree CsgTree::replaceSubtree(const Node* target, const CsgTree& replacement) const {
  if (replacement.empty()) throw std::invalid_argument("replaceSubtree: the replacement is empty");
  NodePtr r = root_ && target ? replaced(root_, target, replacement.root()) : nullptr;
  if (!r) throw std::invalid_argument("replaceSubtree: the node is not in the tree");
  return CsgTree(std::move(r));
}

std::string_view nodeKindName(NodeKind kind) {
  // In the order of NodeKind.
  static constexpr std::array<std::string_view, 5> kNames = {"primitive", "union", "intersection",
                                                             "difference", "complement"};
  const auto i = static_cast<std::size_t>(kind);
  return i < kNames.size() ? kNames[i] : "unknown";
}

}  // namespace csgvox
