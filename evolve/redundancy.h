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

/// normalizeTree, then, repeatedly, the first operation node (in depth-first
/// order) that can be replaced by one of its operands, or lose an operand,
/// with a fitness at least as high, is; until none can. The result's fitness
/// is never lower than the input's.
/// @throw std::invalid_argument as FitnessModel::evaluate.
CsgTree removeRedundancy(const CsgTree& tree, const FitnessModel& model);

}  // namespace csgvox
