#include "optimize/class_cover.h"

#include <algorithm>
#include <cassert>

namespace csgvox {
namespace {

void add(ChannelCounts& a, const ChannelCounts& b) {
  for (std::size_t k = 0; k < a.size(); ++k) a[k] += b[k];
}
void subtract(ChannelCounts& a, const ChannelCounts& b) {
  for (std::size_t k = 0; k < a.size(); ++k) a[k] -= b[k];
}

}  // namespace

ClassCover::ClassCover(const SelectionClasses& classes)
    : classes_(classes), cover_(classes.size(), 0), sum_(classes.size(), 0) {
  reset(std::vector<std::uint8_t>(classes.itemCount(), 0));
}

void ClassCover::reset(std::span<const std::uint8_t> x) {
  assert(x.size() == classes_.itemCount());
  x_.assign(x.begin(), x.end());
  effect_.assign(x.size(), ChannelCounts{});
  std::fill(cover_.begin(), cover_.end(), 0u);
  std::fill(sum_.begin(), sum_.end(), 0u);
  counts_ = {};
  for (std::size_t a = 0; a < x_.size(); ++a) {
    if (!x_[a]) continue;
    for (std::uint32_t c : classes_.classesOf(a)) {
      if (cover_[c]++ == 0) add(counts_, classes_.weight(c));
      sum_[c] += a;
    }
  }
  // Not chosen: the classes no chosen item holds; chosen: those it alone holds.
  for (std::size_t a = 0; a < x_.size(); ++a) {
    const std::uint32_t alone = x_[a] ? 1 : 0;
    for (std::uint32_t c : classes_.classesOf(a)) {
      if (cover_[c] == alone) add(effect_[a], classes_.weight(c));
    }
  }
}

ChannelCounts ClassCover::countsAfterFlip(std::size_t a) const {
  ChannelCounts c = counts_;
  if (x_[a]) {
    subtract(c, effect_[a]);
  } else {
    add(c, effect_[a]);
  }
  return c;
}

// Adding b: a class it newly covers leaves the effect of every other item
// holding it (none of them is chosen); a class covered once before is no
// longer its one chosen item's alone. Removing b undoes the same. b's own
// effect keeps its value: what adding it added is what removing it removes.
void ClassCover::flip(std::size_t b) {
  const bool adding = !x_[b];
  if (adding) {
    add(counts_, effect_[b]);
  } else {
    subtract(counts_, effect_[b]);
  }
  for (std::uint32_t c : classes_.classesOf(b)) {
    const ChannelCounts& w = classes_.weight(c);
    if (adding) {
      if (cover_[c] == 0) {
        for (std::uint32_t a : classes_.itemsOf(c)) {
          if (a != b) subtract(effect_[a], w);
        }
      } else if (cover_[c] == 1) {
        subtract(effect_[sum_[c]], w);
      }
      ++cover_[c];
      sum_[c] += b;
    } else {
      --cover_[c];
      sum_[c] -= b;
      if (cover_[c] == 0) {
        for (std::uint32_t a : classes_.itemsOf(c)) {
          if (a != b) add(effect_[a], w);
        }
      } else if (cover_[c] == 1) {
        add(effect_[sum_[c]], w);
      }
    }
  }
  x_[b] ^= 1;
}

}  // namespace csgvox
