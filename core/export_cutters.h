#pragma once
/// Cutters grown for exact booleans. OpenSCAD's CGAL booleans are exact and
/// FreeCAD's (OpenCASCADE's, as its OpenSCAD importer runs them) fail
/// silently on coplanar faces, so a hole whose end lies on the face it goes
/// through (as the fitted tree places it, to the last bits) leaves a film of
/// that face, or is not cut at all. Exports whose readers run such booleans
/// write every primitive that removes material a little larger.

#include <unordered_set>

#include "core/csg_tree.h"

namespace csgvox {

/// `primitive` with every face moved out by `margin` (scan units): a box's
/// half sizes, a cylinder's radius and half height, a sphere's radius, a
/// torus's minor radius and a half-space's offset grow by it; a cone keeps
/// its slope and its caps move out along the axis.
Primitive grownPrimitive(const Primitive& primitive, double margin);

/// Which leaves of a tree add material and which remove it: a leaf reached
/// through an odd number of subtracted operands (a difference's operands
/// after the first, a complement's operand) removes it. A leaf the tree
/// shares may do both.
struct LeafRoles {
  std::unordered_set<const Node*> adding;    ///< leaves used to add material
  std::unordered_set<const Node*> removing;  ///< leaves used to remove material
};

/// The roles of the leaves of `tree` (empty sets for an empty tree).
LeafRoles leafRoles(const CsgTree& tree);

/// Whether operand `index` of `node` removes what it holds from the rest (a
/// difference's operands after the first, a complement's operand).
bool subtractsOperand(const Node& node, std::size_t index);

}  // namespace csgvox
