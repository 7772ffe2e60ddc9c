#include "core/csg_tree.h"

#include <algorithm>
#include <functional>
#include <stdexcept>

namespace csgvox {
namespace {

NodePtr makeOperation(NodeKind kind, const std::vector<CsgTree>& operands) {
  if (operands.empty()) throw std::invalid_argument("an operation needs at least one operand");
  auto node = std::make_shared<Node>();
  node->kind = kind;
  for (const CsgTree& t : operands) {
    if (t.empty()) throw std::invalid_argument("an operand is an empty tree");
    node->children.push_back(t.root());
  }
  return node;
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

Aabb boundsOf(const Node& node) {
  switch (node.kind) {
    case NodeKind::Primitive: return node.primitive.bounds();
    case NodeKind::Complement: return Aabb::everything();
    case NodeKind::Difference: return boundsOf(*node.children.front());
    case NodeKind::Union: {
      Aabb b;
      for (const NodePtr& c : node.children) b.extend(boundsOf(*c));
      return b;
    }
    case NodeKind::Intersection: {
      Aabb b = Aabb::everything();
      for (const NodePtr& c : node.children) b = b.intersected(boundsOf(*c));
      return b;
    }
  }
  return {};
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

CsgTree CsgTree::leaf(Primitive primitive, std::string name) {
  auto node = std::make_shared<Node>();
  node->kind = NodeKind::Primitive;
  node->primitive = std::move(primitive);
  node->name = std::move(name);
  return CsgTree(std::move(node));
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

double CsgTree::value(const Vec3& p, const SetOperations& ops) const {
  return evaluate(p, ops).f;
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

std::string_view nodeKindName(NodeKind kind) {
  switch (kind) {
    case NodeKind::Primitive: return "primitive";
    case NodeKind::Union: return "union";
    case NodeKind::Intersection: return "intersection";
    case NodeKind::Difference: return "difference";
    case NodeKind::Complement: return "complement";
  }
  return "unknown";
}

}  // namespace csgvox
