#pragma once
/// Redundancy removal for trees that leave the genetic search: no double
/// complement, no operation with a single operand, and no operation node that
/// can be replaced by one of its operands (or lose one of its operands)
/// without lowering the fitness.

#include "core/csg_tree.h"
#include "evolve/fitness.h"

namespace csgvox {

/// Double complements removed, single-operand operations replaced by their
/// operand, repeated operands of an operation dropped, and subtrees that are
/// empty because their operands cancel (X − X, X ∩ ¬X) removed from their
/// parent. The solid is unchanged; the zero set may lose surfaces that bound
/// no volume (the field of X − X is zero on X's surface), which a fitness at
/// the points alone would reward. A tree that is empty as a whole is
/// returned as it was.
CsgTree normalizeTree(const CsgTree& tree);

/// The tree without the subtrees whose solid is provably empty (or of no
/// volume): a difference whose first operand lies inside a subtracted
/// half-space (or outside a subtracted complement of one), an intersection
/// of an operand with a half-space wholly beyond it, an operation whose
/// operands' bounds do not meet (CsgTree::bounds()); with them, an operation
/// left with one operand is replaced by it. An empty operand is dropped from
/// a union and from a difference's cutters, and empties an intersection and
/// a difference it is cut from. The solid is unchanged; so is a tree that
/// holds no such subtree, or that is empty as a whole. Such a subtree
/// changes no point of the solid, yet its field can stand near zero at scan
/// points, which a fitness at the points would reward, and exports that
/// write half-spaces as finite solids must otherwise cut it exactly.
CsgTree withoutEmptySubtrees(const CsgTree& tree);

/// The tree without the operands (a union's members, a difference's cutters, an
/// intersection's operands) whose removal changes less than `minVolume` of its
/// solid. The change is measured by counting the points of a lattice of
/// `spacing` (coarser where the box the operand can change holds more than
/// 2^18 of them) over that box, at which the tree and the tree without the
/// operand disagree, each point standing for spacing³; an operand whose box is
/// unbounded, or whose lattice is too coarse to resolve `minVolume`, is kept.
/// Operands are tried in depth-first order, and the search starts again after
/// each removal. Not exact: each removal may change the solid by up to
/// `minVolume` (a member that only grazes the rest, a cut that only grazes what
/// it cuts). Deterministic.
CsgTree withoutNegligibleOperands(const CsgTree& tree, double spacing, double minVolume);

/// The tree with each surface that two of its leaves share made one leaf, at
/// a union or a difference (depth-first, the first rewrite kept, then the
/// search starts again), in two ways:
///  - two leaf operands (members, or cutters) that one primitive C spans
///    become C;
///  - a surface cut out of two members of a union is cut once, out of the
///    union: union(A − C1, B − C2, …) becomes union(A, B, …) − C, or, where
///    the other members must keep what C would take, union(union(A, B) − C, …).
/// C spans leaves C1 and C2 when they are equal primitives (C is the first),
/// coaxial cylinders of one radius (C covers both lengths), or boxes of one
/// frame whose extents agree along two of its axes (C covers both along the
/// third); "agree" within a quarter of `spacing`. A rewrite is kept when the
/// solid changes by less than `minVolume` over C's box, counted as
/// withoutNegligibleOperands counts it. One primitive fewer per rewrite: a
/// bore cut from a flange and again from its hub, each to its own depth,
/// becomes one bore, and so does a bore cut as two lengths of it.
/// Deterministic.
CsgTree withSharedCuts(const CsgTree& tree, double spacing, double minVolume);

/// withoutEmptySubtrees and normalizeTree, then, repeatedly, the first operation node (in
/// depth-first order) that can be replaced by one of its operands, or lose an operand, with a
/// fitness at least as high, is; until none can. The result's fitness is never lower than that of
/// the input without its empty subtrees.
/// @throw std::invalid_argument as FitnessModel::evaluate.
CsgTree removeRedundancy(const CsgTree& tree, const FitnessModel& model);

}  // namespace csgvox
