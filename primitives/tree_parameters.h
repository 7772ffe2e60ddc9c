#pragma once
/// The primitives of a CSG tree as one vector of shared parameters, so that
/// the relations the regularisation made exact stay exact while the
/// parameters move:
///  * directions (plane normals, box axes, cylinder, cone and torus axes)
///    that are parallel form one direction class; classes that are
///    orthogonal, or are axes of one box, form one frame, which turns as a
///    rigid body (one rotation for all its directions), so parallel stays
///    parallel and orthogonal stays orthogonal;
///  * along a class, every face (a half-space's plane, a box's two faces, a
///    cylinder's or cone's two caps, a torus' centre) is a plane offset; faces
///    at one offset that face the same way in the solid share it (coplanar
///    faces stay coplanar; a cutter's cap on the face it cuts through is not
///    made to coincide with it exactly, which would leave a zero-thickness
///    surface);
///  * axes of one class through one line share that line (coaxial);
///  * equal radii (cylinder, cone, sphere and torus radii) share one radius;
///    equal sphere centres share one centre.
/// Values are compared within a tolerance meant to catch relations that are
/// exact up to rounding, not near-coincidences: snapping faces a few
/// micrometres apart onto one plane made a fillet ring's hidden bottom
/// coincide exactly with the face it stands on, a zero-thickness surface that
/// surface sampling and OpenCASCADE both stumble on.

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "core/csg_tree.h"

namespace csgvox {

/// Options of TreeParameters.
struct TreeParameterOptions {
  double lengthTolerance = 1e-9;  ///< offsets, lines and radii this close are one parameter,
                                  ///< fraction of the tree's scale (see TreeParameters)
  double angleTolerance = 1e-6;   ///< directions this close to parallel (orthogonal) are one
                                  ///< class (one frame), radians
  bool rotate = true;             ///< frames may turn (false: directions are held fixed)
};

/// One block of parameters (what a least-squares solver moves together).
struct ParameterBlock {
  /// What the block holds.
  enum class Kind {
    Rotation,  ///< a frame's rotation vector (3; starts at 0)
    Offset,    ///< a plane offset along a direction class (1)
    Line,      ///< an axis line's two coordinates across its class (2)
    Radius,    ///< a radius (1)
    Centre,    ///< a sphere centre (3)
  };
  Kind kind = Kind::Offset;
  std::size_t offset = 0;  ///< index of its first value in TreeParameters::values()
  int size = 1;            ///< number of values
  bool constant = false;   ///< held fixed (a zero cone radius; a rotation with rotate off)
  std::size_t users = 0;   ///< leaves that use it
};

/// A tree's primitives as functions of shared parameter blocks.
class TreeParameters {
 public:
  /// Describes the leaves of `tree`. `scale` (> 0, e.g. the scan's diagonal)
  /// scales the length tolerance; `pivot` is the point frames turn about.
  /// @throw std::invalid_argument for an empty tree or a scale that is not > 0.
  TreeParameters(const CsgTree& tree, double scale, const Vec3& pivot,
                 const TreeParameterOptions& options = {});
  ~TreeParameters();
  TreeParameters(TreeParameters&&) noexcept;
  TreeParameters& operator=(TreeParameters&&) noexcept;

  /// The parameter values of the tree as given.
  const std::vector<double>& values() const;
  /// The blocks, each a slice of values().
  const std::vector<ParameterBlock>& blocks() const;
  /// Distinct leaves (a leaf node used twice counts once), in depth-first order.
  std::size_t leafCount() const;
  /// The blocks leaf `leaf` depends on, in a fixed order.
  std::span<const std::size_t> leafBlocks(std::size_t leaf) const;
  /// Leaf `leaf`'s primitive from the values of its blocks: `block[k]` points
  /// at the values of leafBlocks(leaf)[k]. Returns false (leaving `out`) when
  /// the values give no valid primitive (a non-positive size or radius).
  bool leafPrimitive(std::size_t leaf, const double* const* block, Primitive& out) const;
  /// Every leaf's primitive from a full value vector (size of values()).
  /// Returns false when one is not valid.
  bool primitives(std::span<const double> values, std::vector<Primitive>& out) const;
  /// The tree with every leaf replaced by `primitives[leaf]` (names and
  /// shared nodes kept).
  /// @throw std::invalid_argument when the count differs from leafCount().
  CsgTree tree(std::span<const Primitive> primitives) const;
  /// The distinct leaf nodes, in depth-first order.
  std::span<const Node* const> leaves() const;
  /// Each leaf's polarity, in the order of leaves(): -1 when it enters the
  /// solid complemented (a cutter), +1 otherwise, as first met depth first.
  std::span<const int> polarities() const;
  /// Blocks used by more than one leaf: the relations kept exact.
  std::size_t sharedBlocks() const;

 private:
  struct Data;
  std::unique_ptr<Data> data_;
};

}  // namespace csgvox
