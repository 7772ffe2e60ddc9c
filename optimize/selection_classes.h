#pragma once
/// The universe of a SelectionProblem cut into classes: the voxels that lie in
/// exactly the same items form one class. Every count the selection solver
/// needs (how many voxels of each channel a union holds, what adding or
/// removing one item changes) is a sum of class weights, so the solver works
/// on a few thousand classes instead of every voxel, and a finer grid adds
/// voxels to the classes far faster than it adds classes. Voxels in no item
/// are in no class (no union ever holds them).

#include <cstdint>
#include <span>
#include <vector>

#include "optimize/branch_and_bound.h"

namespace csgvox {

/// An item given by a generator set: the members of a mask that the
/// generator holds, or, when `complement`, those it does not hold.
struct GeneratedItem {
  std::uint32_t generator = 0;  ///< index of the generator
  bool complement = false;      ///< the mask's members outside the generator
};

/// Classes of a selection's universe, with the items of each class and the
/// classes of each item.
class SelectionClasses {
 public:
  /// The classes of `problem`'s universe, numbered in the order of their first
  /// voxel.
  explicit SelectionClasses(const SelectionProblem& problem);
  /// The classes of a universe given as the members of `mask` (in their
  /// order), without building it: item a is items[a] over `generators` (sets
  /// of mask's size), and channel k's voxels are the members of channels[k]
  /// (at most two, subsets of mask). Works in the generators' own voxel order,
  /// where a class runs along rows of voxels.
  SelectionClasses(std::span<const VoxelSet* const> generators,
                   std::span<const GeneratedItem> items, const VoxelSet& mask,
                   std::span<const VoxelSet* const> channels);

  /// Number of classes.
  std::size_t size() const { return weights_.size(); }
  /// Number of items of the problem.
  std::size_t itemCount() const { return itemStart_.size() - 1; }
  /// Voxels of class c in each channel of the problem (0 beyond its channels).
  const ChannelCounts& weight(std::size_t c) const { return weights_[c]; }
  /// Classes of item a (indices into the problem's items), ascending.
  std::span<const std::uint32_t> classesOf(std::size_t a) const {
    return {itemClasses_.data() + itemStart_[a], itemClasses_.data() + itemStart_[a + 1]};
  }
  /// Items of class c, ascending.
  std::span<const std::uint32_t> itemsOf(std::size_t c) const {
    return {classItems_.data() + classStart_[c], classItems_.data() + classStart_[c + 1]};
  }

 private:
  void build(std::span<const VoxelSet* const> generators, std::span<const GeneratedItem> items,
             const VoxelSet& mask, std::span<const VoxelSet* const> channels);

  std::vector<ChannelCounts> weights_;
  std::vector<std::size_t> itemStart_, classStart_;
  std::vector<std::uint32_t> itemClasses_, classItems_;
};

}  // namespace csgvox
