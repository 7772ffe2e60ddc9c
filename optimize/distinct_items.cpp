#include "optimize/distinct_items.h"

namespace csgvox {
namespace {

std::uint64_t masked(std::uint64_t generator, std::uint64_t mask, bool complement) {
  return complement ? mask & ~generator : mask & generator;
}

}  // namespace

DistinctItems::DistinctItems(const VoxelSet& mask) : mask_(mask) {
  const auto words = mask.words();
  for (std::size_t w = 0; w < words.size(); ++w) {
    if (words[w]) words_.push_back(std::uint32_t(w));
  }
}

bool DistinctItems::same(const Seen& a, const VoxelSet& generator, bool complement) const {
  const auto x = a.generator->words(), y = generator.words(), m = mask_.words();
  for (std::uint32_t w : words_) {
    if (masked(x[w], m[w], a.complement) != masked(y[w], m[w], complement)) return false;
  }
  return true;
}

bool DistinctItems::add(const VoxelSet& generator, bool complement, std::size_t count) {
  for (const Seen& s : seen_) {
    if (s.count == count && same(s, generator, complement)) return false;
  }
  seen_.push_back({&generator, complement, count});
  return true;
}

}  // namespace csgvox
