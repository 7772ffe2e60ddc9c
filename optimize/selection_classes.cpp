#include "optimize/selection_classes.h"

#include <array>
#include <bit>
#include <cassert>

namespace csgvox {
namespace {

using Word = std::uint64_t;

// Transposes a 64 x 64 bit matrix in place: bit j of m[i] becomes bit i of
// m[j]. Each round swaps the off-diagonal blocks of size s within every
// 2s x 2s block.
void transpose64(std::array<Word, 64>& m) {
  Word mask = 0x00000000FFFFFFFFULL;
  for (unsigned s = 32; s != 0; s >>= 1, mask ^= mask << s) {
    for (unsigned k = 0; k < 64; k = ((k | s) + 1) & ~s) {
      const Word t = ((m[k] >> s) ^ m[k | s]) & mask;
      m[k] ^= t << s;
      m[k | s] ^= t;
    }
  }
}

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

}  // namespace

SelectionClasses::SelectionClasses(const SelectionProblem& problem) {
  const auto& items = problem.items();
  const std::size_t n = items.size();
  const std::size_t groups = (n + 63) / 64;
  const std::size_t words = (problem.universe() + 63) / 64;
  RowTable table(groups);
  // The rows of the 64 voxels of one universe word: block[v * groups + g].
  std::vector<Word> block(64 * groups);
  std::array<Word, 64> m;
  for (std::size_t w = 0; w < words; ++w) {
    Word occupied = 0;
    for (std::size_t g = 0; g < groups; ++g) {
      Word any = 0;
      for (std::size_t i = 0; i < 64; ++i) {
        const std::size_t a = g * 64 + i;
        m[i] = a < n ? items[a].set.words()[w] : 0;
        any |= m[i];
      }
      occupied |= any;
      if (any) transpose64(m);
      for (std::size_t v = 0; v < 64; ++v) block[v * groups + g] = any ? m[v] : 0;
    }
    std::array<Word, 2> channel{};
    for (std::size_t k = 0; k < problem.channelCount(); ++k) {
      channel[k] = problem.channel(k).words()[w];
    }
    std::size_t last = std::size_t(-1);
    for (Word bits = occupied; bits; bits &= bits - 1) {
      const std::size_t v = std::size_t(std::countr_zero(bits));
      const Word* row = block.data() + v * groups;
      // Neighbouring voxels mostly share their class.
      if (last == std::size_t(-1) || !sameRow(table.row(last), row, groups)) last = table.find(row);
      if (last == weights_.size()) weights_.push_back({});
      for (std::size_t k = 0; k < channel.size(); ++k) weights_[last][k] += (channel[k] >> v) & 1;
    }
  }
  // Items of each class, then classes of each item (ascending, by counting).
  const std::size_t classes = weights_.size();
  classStart_.assign(classes + 1, 0);
  std::vector<std::size_t> perItem(n + 1, 0);
  for (std::size_t c = 0; c < classes; ++c) {
    const Word* row = table.row(c);
    for (std::size_t g = 0; g < groups; ++g) {
      for (Word bits = row[g]; bits; bits &= bits - 1) {
        const std::size_t a = g * 64 + std::size_t(std::countr_zero(bits));
        classItems_.push_back(std::uint32_t(a));
        ++perItem[a + 1];
      }
    }
    classStart_[c + 1] = classItems_.size();
  }
  itemStart_.assign(n + 1, 0);
  for (std::size_t a = 0; a < n; ++a) itemStart_[a + 1] = itemStart_[a] + perItem[a + 1];
  itemClasses_.resize(classItems_.size());
  std::vector<std::size_t> next(itemStart_.begin(), itemStart_.end() - 1);
  for (std::size_t c = 0; c < classes; ++c) {
    for (std::uint32_t a : itemsOf(c)) itemClasses_[next[a]++] = std::uint32_t(c);
  }
  assert(n == 0 || next.back() == itemStart_[n]);
}

}  // namespace csgvox
