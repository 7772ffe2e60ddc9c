#pragma once
/// A CSG tree compiled to a flat postfix program over its leaves, for the hot
/// evaluation paths: values without gradients, recursion or virtual calls,
/// batched over arrays of points (each leaf and each operation applied to a
/// whole chunk of points), and restriction to a region, which drops the
/// subtrees that cannot change the field near the surface there (meshing of
/// trees with many leaves).

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/csg_tree.h"

namespace csgvox {

/// A compiled CSG tree. Values are bit for bit those of CsgTree::value and
/// CsgTree::evaluate (min/max unless told otherwise). Immutable and safe to
/// share between threads.
class TreeProgram {
 public:
  /// The program of an empty tree (value -inf everywhere).
  TreeProgram();
  /// Compiles `tree` (time and memory linear in its number of nodes).
  explicit TreeProgram(const CsgTree& tree);

  /// Value at p with min/max.
  double value(const Vec3& p) const;
  /// Value and gradient at p with min/max.
  FieldValue evaluate(const Vec3& p) const;
  /// out[i] = value at points[i] with the set operations `ops`. From 4096
  /// points on, the points are split among the threads (TBB); every value is
  /// its point's alone, so the values are the same on any number of threads.
  /// @throw std::invalid_argument when the spans differ in size, or for
  ///        SetOperationKind::Sardf (which needs a radius: pass the
  ///        SardfOperations object to the overload below).
  void values(std::span<const Vec3> points, std::span<double> out,
              SetOperationKind ops = SetOperationKind::MinMax) const;
  /// out[i] = value at points[i] with the set operations `ops` (bit for bit
  /// CsgTree::value(points[i], ops)); SardfOperations with its radius.
  /// @throw std::invalid_argument when the spans differ in size, or `ops` is
  ///        of kind Sardf without being a SardfOperations.
  void values(std::span<const Vec3> points, std::span<double> out, const SetOperations& ops) const;

  /// A program for the points of `region` (min/max only), for a threshold
  /// T = `threshold`: at every point of the region where this program's
  /// |value| < T, the restricted program gives the same value and gradient,
  /// bit for bit; elsewhere it gives a value of the same sign with |value|
  /// >= T. Subtrees whose value is below -T (or above T) all over the region
  /// become constants and are dropped from unions (intersections). Relies on
  /// the field being 1-Lipschitz (exact primitive distances with min/max).
  /// @throw std::invalid_argument when `threshold` is not > 0 or exceeds this
  ///        program's own threshold, or the region is empty or unbounded.
  TreeProgram restricted(const Aabb& region, double threshold) const;

  /// The threshold below which values are exact (+inf for a whole tree).
  double threshold() const { return threshold_; }
  /// Number of leaves the program evaluates.
  std::size_t leafCount() const;
  /// True when the program is a constant (no leaf left).
  bool isConstant() const { return leafCount() == 0; }

 private:
  enum class Op : std::uint8_t { Leaf, Constant, Negate, Unite, Intersect };
  struct Step {
    Op op = Op::Constant;
    std::uint32_t leaf = 0;  // Leaf: index into the shared leaves
    double constant = 0.0;   // Constant: its value
  };
  struct Leaves {
    std::vector<Primitive> primitives;
    std::vector<Aabb> bounds;
  };

  void compile(const Node& node, Leaves& leaves);
  static std::size_t depthOf(const std::vector<Step>& steps);
  template <class Ops>
  void runValues(std::span<const Vec3> points, std::span<double> out, const Ops& ops) const;

  std::shared_ptr<const Leaves> leaves_;
  std::vector<Step> steps_;
  std::size_t stackDepth_ = 1;  // most values held at once
  double threshold_;
};

}  // namespace csgvox
