#include "optimize/selection_classes.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>

namespace csgvox {
namespace {

using Word = std::uint64_t;

Word hashRow(const Word* row, std::size_t words) {
  Word h = 0x84222325cbf29ce4ULL;
  for (std::size_t g = 0; g < words; ++g) {
    h = (h ^ row[g]) * 0x9e3779b97f4a7c15ULL;
    h ^= h >> 29;
  }
  return h;
}

bool sameRow(const Word* a, const Word* b, std::size_t words) {
  for (std::size_t g = 0; g < words; ++g) {
    if (a[g] != b[g]) return false;
  }
  return true;
}

// Rows (one bit per item) of the classes found so far, and an open-addressing
// table from a row to its class.
class RowTable {
 public:
  explicit RowTable(std::size_t words) : words_(words), slots_(1024, kEmpty) {}

  // The class of `row`, a new one (numbered next) when the row is new.
  std::uint32_t find(const Word* row) {
    if (2 * (classes() + 1) > slots_.size()) grow();
    const Word h = hashRow(row, words_);
    for (std::size_t s = h & (slots_.size() - 1);; s = (s + 1) & (slots_.size() - 1)) {
      const std::uint32_t c = slots_[s];
      if (c == kEmpty) {
        slots_[s] = std::uint32_t(classes());
        rows_.insert(rows_.end(), row, row + words_);
        return slots_[s];
      }
      if (sameRow(this->row(c), row, words_)) return c;
    }
  }
  const Word* row(std::size_t c) const { return rows_.data() + c * words_; }
  std::size_t classes() const { return words_ ? rows_.size() / words_ : 0; }

 private:
  static constexpr std::uint32_t kEmpty = ~std::uint32_t(0);

  void grow() {
    std::vector<std::uint32_t> bigger(2 * slots_.size(), kEmpty);
    for (std::size_t c = 0; c < classes(); ++c) {
      std::size_t s = hashRow(row(c), words_) & (bigger.size() - 1);
      while (bigger[s] != kEmpty) s = (s + 1) & (bigger.size() - 1);
      bigger[s] = std::uint32_t(c);
    }
    slots_ = std::move(bigger);
  }

  std::size_t words_;
  std::vector<std::uint32_t> slots_;
  std::vector<Word> rows_;
};

// The generators of some item, which alone split classes: bit b of a row is
// generator used[b], bitOf[generator] its bit (~0: in no item).
struct UsedGenerators {
  std::vector<std::uint32_t> bitOf;
  std::vector<const Word*> used;
};

// The generators the items use, in the order of their first item.
UsedGenerators usedGenerators(std::span<const VoxelSet* const> generators,
                              std::span<const GeneratedItem> items) {
  UsedGenerators u{std::vector<std::uint32_t>(generators.size(), ~std::uint32_t(0)), {}};
  for (const GeneratedItem& item : items) {
    if (u.bitOf[item.generator] == ~std::uint32_t(0)) {
      u.bitOf[item.generator] = std::uint32_t(u.used.size());
      u.used.push_back(generators[item.generator]->words().data());
    }
  }
  return u;
}

// The walk of SelectionClasses::build over the mask's words: the row (the
// generators holding the current voxel), its class once looked up, and the
// voxels of each class in each channel.
struct ClassWalk {
  static constexpr std::size_t kUnknown = std::size_t(-1);
  std::span<const Word* const> used;  // bit b of a row: generator used[b]
  std::span<const VoxelSet* const> channels;
  std::vector<ChannelCounts>& weights;  // of each class
  std::size_t g = used.size();
  std::size_t rowWords = std::max<std::size_t>(1, (g + 63) / 64);
  RowTable table{rowWords};
  std::vector<Word> row = std::vector<Word>(rowWords, 0);  // generators holding the current voxel
  // Generator b's bit of the voxel before this word.
  std::vector<Word> below = std::vector<Word>(g, 0);
  std::vector<std::uint32_t> changes{};  // (bit << 20 | b) where generator b starts or stops
  std::vector<std::uint32_t> byBit{};    // the generators of `changes`, by bit
  std::size_t current = kUnknown;        // the current row's class, once looked up

  // The row of the voxel before word w, from scratch.
  void restart(std::size_t w) {
    std::fill(row.begin(), row.end(), 0);
    for (std::size_t b = 0; b < g; ++b) {
      below[b] = w > 0 ? used[b][w - 1] >> 63 : 0;
      row[b / 64] |= below[b] << (b % 64);
    }
    current = kUnknown;
  }

  // Where generators start or stop in word w: `changes`, their number at
  // each bit in perBit, and the bits where any does (returned).
  Word findChanges(std::size_t w, std::array<std::uint32_t, 64>& perBit) {
    changes.clear();
    Word changed = 0;
    for (std::size_t b = 0; b < g; ++b) {
      const Word x = used[b][w];
      const Word flips = x ^ ((x << 1) | below[b]);
      below[b] = x >> 63;
      changed |= flips;
      for (Word bits = flips; bits; bits &= bits - 1) {
        const std::uint32_t bit = std::uint32_t(std::countr_zero(bits));
        changes.push_back(bit << 20 | std::uint32_t(b));
        ++perBit[bit];
      }
    }
    return changed;
  }

  // Voxels [from, to) of this word (mask bits m, the channels' words
  // `channel`) are in the current row's class.
  void credit(std::size_t from, std::size_t to, Word m, const std::array<Word, 2>& channel) {
    if (from == to) return;
    const Word run = (to == 64 ? ~Word(0) : (Word(1) << to) - 1) & ~((Word(1) << from) - 1);
    if ((m & run) == 0) return;
    if (current == kUnknown) {
      current = table.find(row.data());
      if (current == weights.size()) weights.push_back({});
    }
    for (std::size_t k = 0; k < channels.size(); ++k) {
      weights[current][k] += std::size_t(std::popcount(channel[k] & run));
    }
  }

  // Counts the voxels of word w (mask bits m) into their classes.
  void walkWord(std::size_t w, Word m) {
    std::array<std::uint32_t, 64> perBit{};
    const Word changed = findChanges(w, perBit);  // bits where some generator starts or stops
    // The generators by bit (a counting sort): bit v's at [first[v], first[v] + perBit[v]).
    std::array<std::uint32_t, 64> first{};
    for (std::uint32_t v = 1, sum = 0; v < 64; ++v) first[v] = sum += perBit[v - 1];
    byBit.resize(changes.size());
    {
      std::array<std::uint32_t, 64> next = first;
      for (std::uint32_t c : changes) byBit[next[c >> 20]++] = c & ((1u << 20) - 1);
    }
    std::array<Word, 2> channel{};
    for (std::size_t k = 0; k < channels.size(); ++k) channel[k] = channels[k]->words()[w];
    std::size_t from = 0;
    for (Word bits = changed; bits; bits &= bits - 1) {
      const std::size_t bit = std::size_t(std::countr_zero(bits));
      credit(from, bit, m, channel);
      for (std::uint32_t c = first[bit]; c < first[bit] + perBit[bit]; ++c) {
        row[byBit[c] / 64] ^= Word(1) << (byBit[c] % 64);
      }
      current = kUnknown;
      from = bit;
    }
    credit(from, 64, m, channel);
  }
};

}  // namespace

SelectionClasses::SelectionClasses(const SelectionProblem& problem) {
  std::vector<const VoxelSet*> generators, channels;
  std::vector<GeneratedItem> items;
  for (const SelectionItem& item : problem.items()) {
    items.push_back({std::uint32_t(generators.size()), false});
    generators.push_back(&item.set);
  }
  for (std::size_t k = 0; k < problem.channelCount(); ++k) channels.push_back(&problem.channel(k));
  build(generators, items, VoxelSet(problem.universe()).complemented(), channels);
}

SelectionClasses::SelectionClasses(std::span<const VoxelSet* const> generators,
                                   std::span<const GeneratedItem> items, const VoxelSet& mask,
                                   std::span<const VoxelSet* const> channels) {
  build(generators, items, mask, channels);
}

// Walks the mask's words in order keeping the row (the generators holding
// the current voxel) up to date from where generators start and stop: a word
// costs one pass over the generators plus the few places where some
// generator's membership changes, and a class is looked up only there.
void SelectionClasses::build(std::span<const VoxelSet* const> generators,
                             std::span<const GeneratedItem> items, const VoxelSet& mask,
                             std::span<const VoxelSet* const> channels) {
  assert(channels.size() <= ChannelCounts().size());
  const UsedGenerators u = usedGenerators(generators, items);
  assert(u.used.size() < (1u << 20));
  ClassWalk walk{u.used, channels, weights_};
  const auto maskWords = mask.words();
  bool continuous = false;  // the previous word was walked
  for (std::size_t w = 0; w < maskWords.size(); ++w) {
    const Word m = maskWords[w];
    if (m == 0) {
      continuous = false;
      continue;
    }
    if (!continuous) {
      walk.restart(w);
      continuous = true;
    }
    walk.walkWord(w, m);
  }
  // Items of each class (a class in no item is dropped), then classes of
  // each item (ascending, by counting).
  const std::size_t n = items.size();
  std::vector<std::size_t> perItem(n + 1, 0);
  std::vector<ChannelCounts> kept;
  classStart_.assign(1, 0);
  for (std::size_t c = 0; c < weights_.size(); ++c) {
    const Word* r = walk.table.row(c);
    const std::size_t first = classItems_.size();
    for (std::size_t a = 0; a < n; ++a) {
      const std::uint32_t b = u.bitOf[items[a].generator];
      if (bool(r[b / 64] >> (b % 64) & 1) != items[a].complement) {
        classItems_.push_back(std::uint32_t(a));
        ++perItem[a + 1];
      }
    }
    if (classItems_.size() == first) continue;
    kept.push_back(weights_[c]);
    classStart_.push_back(classItems_.size());
  }
  weights_ = std::move(kept);
  const std::size_t classes = weights_.size();
  itemStart_.assign(n + 1, 0);
  for (std::size_t a = 0; a < n; ++a) itemStart_[a + 1] = itemStart_[a] + perItem[a + 1];
  itemClasses_.resize(classItems_.size());
  std::vector<std::size_t> next(itemStart_.begin(), itemStart_.end() - 1);
  for (std::size_t c = 0; c < classes; ++c) {
    for (std::uint32_t a : itemsOf(c)) itemClasses_[next[a]++] = std::uint32_t(c);
  }
}

}  // namespace csgvox
