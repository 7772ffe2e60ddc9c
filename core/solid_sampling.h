#pragma once
/// Volume and overlap of CSG solids by stratified sampling: one random point
/// in each cell of a grid over a box, so that the error comes only from the
/// cells the surface crosses, and no layer of samples lines up with a face
/// (as cell centres do with parts dimensioned in round numbers).

#include <array>
#include <cstdint>
#include <vector>

#include "core/csg_tree.h"

namespace csgvox {

/// One uniform random point in every cell of a grid of `cells` cells per
/// axis over `box`, x fastest; deterministic for a seed.
std::vector<Vec3> stratifiedPoints(const Aabb& box, const std::array<int, 3>& cells,
                                   std::uint64_t seed);
/// The same with n cells along every axis.
std::vector<Vec3> stratifiedPoints(const Aabb& box, int n, std::uint64_t seed);

/// The volume of the tree's solid inside `box`, from n³ stratified points.
/// @throw std::invalid_argument when n < 1 or the box is empty or unbounded.
double sampledVolume(const CsgTree& tree, const Aabb& box, int n, std::uint64_t seed = 1);

/// Volumetric IoU of two solids over the box holding both (their bounds),
/// from stratified points in cubic cells, `resolution` along the box's
/// longest side; 1 when both are empty. The points are made and classified
/// one layer at a time, so memory stays small at any resolution.
/// @throw std::invalid_argument when a tree is empty or unbounded, or
///        resolution < 2.
double volumetricIou(const CsgTree& a, const CsgTree& b, int resolution = 200,
                     std::uint64_t seed = 1);

}  // namespace csgvox
