#pragma once
/// Incremental bookkeeping for set-cover style local search: how many chosen
/// sets cover each voxel, with bitsets of the voxels covered at least once and
/// exactly once, so that the effect of adding or removing one set is a single
/// AND/AND-NOT plus popcount.

#include "voxel/voxel_set.h"

#include <bit>
#include <cstdint>
#include <vector>

namespace csgvox {

/// Coverage counts over a universe of `size` voxels.
class CoverState {
 public:
  explicit CoverState(std::size_t size) : counts_(size, 0), covered_(size), once_(size) {}

  const VoxelSet& covered() const { return covered_; }
  /// Members of `s` that adding it would newly cover.
  std::size_t gain(const VoxelSet& s) const { return VoxelSet::countAndNot(s, covered_); }
  /// Members of `s` that removing it (it must be chosen) would uncover.
  std::size_t loss(const VoxelSet& s) const { return VoxelSet::countAnd(s, once_); }

  void add(const VoxelSet& s) { update(s, +1); }
  void remove(const VoxelSet& s) { update(s, -1); }

 private:
  void update(const VoxelSet& s, int delta) {
    const auto words = s.words();
    for (std::size_t w = 0; w < words.size(); ++w) {
      for (std::uint64_t bits = words[w]; bits; bits &= bits - 1) {
        const std::size_t i = w * 64 + std::size_t(std::countr_zero(bits));
        const int c = int(counts_[i]) + delta;
        counts_[i] = std::uint32_t(c);
        if (c > 0) covered_.set(i); else covered_.reset(i);
        if (c == 1) once_.set(i); else once_.reset(i);
      }
    }
  }

  std::vector<std::uint32_t> counts_;
  VoxelSet covered_;
  VoxelSet once_;
};

}  // namespace csgvox
