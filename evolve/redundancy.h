#pragma once
/// Redundancy removal for trees that leave the genetic search: no double
/// complement, no operation with a single operand, and no operation node that
/// can be replaced by one of its operands (or lose one of its operands)
/// without lowering the fitness.

#include "core/csg_tree.h"
#include "evolve/fitness.h"

namespace csgvox {

/// Double complements removed and single-operand operations replaced by their
/// operand. The solid is unchanged.
CsgTree normalizeTree(const CsgTree& tree);

/// normalizeTree, then, repeatedly, the first operation node (in depth-first
/// order) that can be replaced by one of its operands, or lose an operand,
/// with a fitness at least as high, is; until none can. The result's fitness
/// is never lower than the input's.
/// @throw std::invalid_argument as FitnessModel::evaluate.
CsgTree removeRedundancy(const CsgTree& tree, const FitnessModel& model);

}  // namespace csgvox
