#include "voxel/voxel_set.h"

#include <algorithm>
#include <bit>
#include <cassert>

#include "voxel/bitset_kernels.h"

// The word-wise operations run on activeBitsetKernels(): the kernels of the
// instruction-set level in use, chosen per call (core/cpu_features.h).

namespace csgvox {

void VoxelSet::fill() {
  std::fill(words_.begin(), words_.end(), ~std::uint64_t(0));
  clearPadding();
}

void VoxelSet::clear() { std::fill(words_.begin(), words_.end(), 0); }

void VoxelSet::clearPadding() {
  if (bits_ % 64 != 0 && !words_.empty()) {
    words_.back() &= (std::uint64_t(1) << (bits_ % 64)) - 1;
  }
}

std::size_t VoxelSet::count() const {
  return activeBitsetKernels().count(words_.data(), words_.size());
}

bool VoxelSet::none() const {
  return std::all_of(words_.begin(), words_.end(), [](std::uint64_t w) { return w == 0; });
}

VoxelSet& VoxelSet::operator&=(const VoxelSet& other) {
  assert(bits_ == other.bits_);
  activeBitsetKernels().andInPlace(words_.data(), other.words_.data(), words_.size());
  return *this;
}

VoxelSet& VoxelSet::operator|=(const VoxelSet& other) {
  assert(bits_ == other.bits_);
  activeBitsetKernels().orInPlace(words_.data(), other.words_.data(), words_.size());
  return *this;
}

VoxelSet& VoxelSet::subtract(const VoxelSet& other) {
  assert(bits_ == other.bits_);
  activeBitsetKernels().andNotInPlace(words_.data(), other.words_.data(), words_.size());
  return *this;
}

std::vector<std::uint32_t> VoxelSet::members() const {
  std::vector<std::uint32_t> out;
  out.reserve(count());
  for (std::size_t w = 0; w < words_.size(); ++w) {
    for (std::uint64_t bits = words_[w]; bits; bits &= bits - 1) {
      out.push_back(std::uint32_t(w * 64 + std::size_t(std::countr_zero(bits))));
    }
  }
  return out;
}

VoxelSet VoxelSet::gather(std::span<const std::uint32_t> positions) const {
  VoxelSet local(positions.size());
  for (std::size_t p = 0; p < positions.size(); ++p) {
    if (test(positions[p])) local.set(p);
  }
  return local;
}

VoxelSet VoxelSet::compress(const VoxelSet& mask) const {
  assert(bits_ == mask.bits_);
  VoxelSet local(mask.count());
  activeBitsetKernels().compress(words_.data(), mask.words_.data(), words_.size(),
                                 local.words_.data());
  return local;
}

VoxelSet VoxelSet::complemented() const {
  VoxelSet c = *this;
  for (std::uint64_t& w : c.words_) w = ~w;
  c.clearPadding();
  return c;
}

std::size_t VoxelSet::countAnd(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  return activeBitsetKernels().countAnd(a.words_.data(), b.words_.data(), a.words_.size());
}

std::size_t VoxelSet::countAndNot(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  return activeBitsetKernels().countAndNot(a.words_.data(), b.words_.data(), a.words_.size());
}

double VoxelSet::iou(const VoxelSet& a, const VoxelSet& b) {
  const std::size_t either = countOr(a, b);
  return either == 0 ? 1.0 : double(countAnd(a, b)) / double(either);
}

std::size_t VoxelSet::countOr(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  return activeBitsetKernels().countOr(a.words_.data(), b.words_.data(), a.words_.size());
}

bool VoxelSet::intersects(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  return activeBitsetKernels().intersects(a.words_.data(), b.words_.data(), a.words_.size());
}

}  // namespace csgvox
