#pragma once
/// The CSG tree: an immutable FRep value. Leaves are primitives; inner nodes
/// are union, intersection, difference (first child minus the others) and
/// complement. Edits return new trees that share unchanged subtrees.
/// Evaluation: value() per point and values() over arrays of points give the
/// field without gradients (bit for bit the f of evaluate(), which alone
/// computes gradients); core/tree_program.h compiles a tree once for repeated
/// use and prunes it to a region.

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/primitive.h"
#include "core/set_operations.h"

namespace csgvox {

/// Kind of a tree node.
enum class NodeKind { Primitive, Union, Intersection, Difference, Complement };

struct Node;
/// Nodes are shared and never modified after construction.
using NodePtr = std::shared_ptr<const Node>;

/// The payload of a leaf node.
struct LeafData {
  Primitive primitive;  ///< the leaf's solid
  std::string name;     ///< optional label, e.g. "hole1"
};

/// One node of a CSG tree. Only leaves hold a LeafData; `primitive` and
/// `name` read it (on an operation node they read a shared default: the
/// half-space z <= 0 and an empty name). Nodes are not copyable: `primitive`
/// and `name` refer to the node's own payload.
struct Node {
  /// A leaf.
  explicit Node(Primitive leafPrimitive = {}, std::string leafName = {});
  /// An operation node (kind != Primitive) with its operands.
  Node(NodeKind operation, std::vector<NodePtr> operands);
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  NodeKind kind = NodeKind::Primitive;
  std::vector<NodePtr> children;  ///< operands of an operation, in order

 private:
  std::unique_ptr<const LeafData> leaf_;  // null on operation nodes

 public:
  const Primitive& primitive;  ///< the leaf's primitive (kind == Primitive only)
  const std::string& name;     ///< optional label of a leaf, e.g. "hole1"
};

/// A node's place in a tree: the child index taken at each level from the
/// root (empty for the root itself).
using NodePath = std::vector<std::size_t>;

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
  /// Each leaf node once (a node shared by two branches once), in the
  /// depth-first order of its first use.
  std::vector<const Node*> distinctLeaves() const;

  /// FRep value at p (>= 0 inside), without gradients: bit for bit the f of
  /// evaluate(p, ops). -inf for an empty tree.
  double value(const Vec3& p, const SetOperations& ops = minMaxOperations()) const;
  /// out[i] = value(points[i]) for every point (bit for bit), evaluating each
  /// leaf and each operation over whole arrays of points (see TreeProgram).
  /// @throw std::invalid_argument when the spans differ in size, or for
  ///        SetOperationKind::Sardf (which needs a radius: pass the
  ///        SardfOperations object to the overload below).
  void values(std::span<const Vec3> points, std::span<double> out,
              SetOperationKind ops = SetOperationKind::MinMax) const;
  /// out[i] = value(points[i], ops) for every point (bit for bit), batched as
  /// above; any built-in implementation, SardfOperations with its radius.
  /// @throw std::invalid_argument when the spans differ in size, or `ops` is
  ///        of kind Sardf without being a SardfOperations.
  void values(std::span<const Vec3> points, std::span<double> out, const SetOperations& ops) const;
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
  /// Hash of the structure (node kinds, arity, order, primitive parameters;
  /// leaf names ignored): trees equal by structurallyEqual(other, 0) hash
  /// equal. Takes time linear in the number of nodes. 0 for an empty tree.
  std::size_t structuralHash() const;

  /// The node at `path`. @throw std::out_of_range when the path leaves the tree.
  const NodePtr& nodeAt(const NodePath& path) const;
  /// The tree with the node at `path` replaced by `replacement`; every subtree
  /// off the path is shared with this tree.
  /// @throw std::out_of_range when the path leaves the tree;
  ///        std::invalid_argument when `replacement` is empty.
  CsgTree replaceSubtree(const NodePath& path, const CsgTree& replacement) const;
  /// The tree with every occurrence of `target` (compared by address: a shared
  /// subtree is replaced wherever it is used) replaced by `replacement`.
  /// @throw std::invalid_argument when `target` is not in the tree or
  ///        `replacement` is empty.
  CsgTree replaceSubtree(const Node* target, const CsgTree& replacement) const;

 private:
  NodePtr root_;
};

/// Hash functor for unordered containers keyed by trees (fitness caches).
struct CsgTreeHash {
  std::size_t operator()(const CsgTree& tree) const { return tree.structuralHash(); }
};

/// Lower-case operation name used in files: "union", "intersection",
/// "difference", "complement" ("primitive" for leaves).
std::string_view nodeKindName(NodeKind kind);

}  // namespace csgvox
