#pragma once
/// The CSG tree: an immutable FRep value. Leaves are primitives; inner nodes
/// are union, intersection, difference (first child minus the others) and
/// complement. Edits return new trees that share unchanged subtrees.

#include "core/primitive.h"
#include "core/set_operations.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace csgvox {

/// Kind of a tree node.
enum class NodeKind { Primitive, Union, Intersection, Difference, Complement };

struct Node;
/// Nodes are shared and never modified after construction.
using NodePtr = std::shared_ptr<const Node>;

/// One node of a CSG tree.
struct Node {
  NodeKind kind = NodeKind::Primitive;
  Primitive primitive;            ///< the leaf's primitive (kind == Primitive only)
  std::string name;               ///< optional label of a leaf, e.g. "hole1"
  std::vector<NodePtr> children;  ///< operands of an operation, in order
};

/// A CSG tree (possibly empty), held by value.
class CsgTree {
 public:
  CsgTree() = default;
  explicit CsgTree(NodePtr root) : root_(std::move(root)) {}

  /// A single-primitive tree.
  static CsgTree leaf(Primitive primitive, std::string name = {});
  /// n-ary union (at least one operand).
  static CsgTree unite(const std::vector<CsgTree>& operands);
  /// n-ary intersection (at least one operand).
  static CsgTree intersect(const std::vector<CsgTree>& operands);
  /// operands[0] minus every later operand (at least one operand).
  static CsgTree subtract(const std::vector<CsgTree>& operands);
  /// Complement of a tree.
  static CsgTree complement(const CsgTree& operand);

  const NodePtr& root() const { return root_; }
  bool empty() const { return root_ == nullptr; }

  /// Number of nodes (leaves and operations).
  std::size_t nodeCount() const;
  /// Number of operation nodes.
  std::size_t operationCount() const;
  /// Number of leaves (a primitive used twice counts twice).
  std::size_t primitiveCount() const;
  /// Depth: 0 for an empty tree, 1 for a single leaf.
  std::size_t depth() const;
  /// The leaves in depth-first order.
  std::vector<const Node*> leaves() const;

  /// FRep value at p (>= 0 inside).
  double value(const Vec3& p, const SetOperations& ops = minMaxOperations()) const;
  /// FRep value and gradient at p.
  FieldValue evaluate(const Vec3& p, const SetOperations& ops = minMaxOperations()) const;
  /// True when p is inside or on the solid.
  bool contains(const Vec3& p) const { return value(p) >= 0.0; }

  /// Conservative axis-aligned bounds of the solid (unbounded if the solid is).
  Aabb bounds() const;

  /// Checks every node (arity, primitive parameters).
  /// @throw std::invalid_argument describing the first problem found.
  void validate() const;

  /// Same shape of tree, same operations, primitives equal within tolerance.
  /// Leaf names are ignored.
  bool structurallyEqual(const CsgTree& other, double tolerance = 0.0) const;
  bool operator==(const CsgTree& other) const { return structurallyEqual(other); }

 private:
  NodePtr root_;
};

/// Lower-case operation name used in files: "union", "intersection",
/// "difference", "complement" ("primitive" for leaves).
std::string_view nodeKindName(NodeKind kind);

}  // namespace csgvox
