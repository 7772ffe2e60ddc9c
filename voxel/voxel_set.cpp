#include "voxel/voxel_set.h"

#include <algorithm>
#include <bit>
#include <cassert>

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
  std::size_t n = 0;
  for (std::uint64_t w : words_) n += std::size_t(std::popcount(w));
  return n;
}

bool VoxelSet::none() const {
  return std::all_of(words_.begin(), words_.end(), [](std::uint64_t w) { return w == 0; });
}

VoxelSet& VoxelSet::operator&=(const VoxelSet& other) {
  assert(bits_ == other.bits_);
  const std::size_t n = words_.size();
  std::uint64_t* __restrict a = words_.data();
  const std::uint64_t* __restrict b = other.words_.data();
  for (std::size_t i = 0; i < n; ++i) a[i] &= b[i];
  return *this;
}

VoxelSet& VoxelSet::operator|=(const VoxelSet& other) {
  assert(bits_ == other.bits_);
  const std::size_t n = words_.size();
  std::uint64_t* __restrict a = words_.data();
  const std::uint64_t* __restrict b = other.words_.data();
  for (std::size_t i = 0; i < n; ++i) a[i] |= b[i];
  return *this;
}

VoxelSet& VoxelSet::subtract(const VoxelSet& other) {
  assert(bits_ == other.bits_);
  const std::size_t n = words_.size();
  std::uint64_t* __restrict a = words_.data();
  const std::uint64_t* __restrict b = other.words_.data();
  for (std::size_t i = 0; i < n; ++i) a[i] &= ~b[i];
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

VoxelSet VoxelSet::complemented() const {
  VoxelSet c = *this;
  for (std::uint64_t& w : c.words_) w = ~w;
  c.clearPadding();
  return c;
}

std::size_t VoxelSet::countAnd(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  const std::size_t n = a.words_.size();
  const std::uint64_t* __restrict x = a.words_.data();
  const std::uint64_t* __restrict y = b.words_.data();
  std::size_t c = 0;
  for (std::size_t i = 0; i < n; ++i) c += std::size_t(std::popcount(x[i] & y[i]));
  return c;
}

std::size_t VoxelSet::countAndNot(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  const std::size_t n = a.words_.size();
  const std::uint64_t* __restrict x = a.words_.data();
  const std::uint64_t* __restrict y = b.words_.data();
  std::size_t c = 0;
  for (std::size_t i = 0; i < n; ++i) c += std::size_t(std::popcount(x[i] & ~y[i]));
  return c;
}

std::size_t VoxelSet::countOr(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  const std::size_t n = a.words_.size();
  const std::uint64_t* __restrict x = a.words_.data();
  const std::uint64_t* __restrict y = b.words_.data();
  std::size_t c = 0;
  for (std::size_t i = 0; i < n; ++i) c += std::size_t(std::popcount(x[i] | y[i]));
  return c;
}

bool VoxelSet::intersects(const VoxelSet& a, const VoxelSet& b) {
  assert(a.bits_ == b.bits_);
  const std::size_t n = a.words_.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (a.words_[i] & b.words_[i]) return true;
  }
  return false;
}

}  // namespace csgvox
