#pragma once
/// Keeps one item per distinct set among items given by generators over a
/// mask (optimize/selection_classes.h): an item whose set equals an earlier
/// item's is refused, as SelectionProblem::add refuses it, without building
/// either set.

#include <cstdint>
#include <vector>

#include "optimize/selection_classes.h"

namespace csgvox {

/// The distinct items seen so far over one mask.
class DistinctItems {
 public:
  /// Items over the members of `mask`, which must outlive this object.
  explicit DistinctItems(const VoxelSet& mask);

  /// Adds the item `complement ? mask \ generator : mask ∩ generator`, which
  /// has `count` members, unless an item with the same set was added;
  /// returns whether it was added. `generator` must outlive this object.
  bool add(const VoxelSet& generator, bool complement, std::size_t count);

 private:
  struct Seen {
    const VoxelSet* generator;
    bool complement;
    std::size_t count;
  };
  bool same(const Seen& a, const VoxelSet& generator, bool complement) const;

  const VoxelSet& mask_;
  std::vector<std::uint32_t> words_;  // the mask's non-zero words
  std::vector<Seen> seen_;
};

}  // namespace csgvox
