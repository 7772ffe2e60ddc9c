// The selection solver on voxel classes (optimize/selection_classes.h,
// optimize/class_cover.h) against the previous exact computation on every
// voxel: the same classes' counts, the same cached flip effects as
// recomputing them with coverage bitsets (optimize/cover_state.h), and the
// same selections, energies and early stops as the previous solver (bitset
// descent and bitset branch and bound, kept here as the reference) on random
// problems and on the phase-1 and phase-2 problems of a real bundled part.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <limits>
#include <random>

#include "io/tree_json.h"
#include "mesh/surface_sampler.h"
#include "optimize/branch_and_bound.h"
#include "optimize/class_cover.h"
#include "optimize/cover_state.h"
#include "optimize/selection_classes.h"
#include "optimize/subtree_selection.h"
#include "optimize/union_selection.h"
#include "part_list.h"
#include "pipeline/detect_and_fit.h"
#include "random_voxel_sets.h"
#include "voxel/description_sets.h"
#include "voxel/labeling.h"

namespace csgvox {
namespace {

using test::randomSet;

// ---- The previous solver, on every voxel (the reference). ----

struct RefItem {
  VoxelSet set;
  std::array<VoxelSet, 2> parts;
  std::vector<std::uint32_t> words;
};

std::vector<RefItem> refItems(const SelectionProblem& pb) {
  std::vector<RefItem> items;
  for (const SelectionItem& it : pb.items()) {
    RefItem r{it.set, {}, nonZeroWords(it.set)};
    for (std::size_t k = 0; k < pb.channelCount(); ++k) r.parts[k] = it.set & pb.channel(k);
    items.push_back(std::move(r));
  }
  return items;
}

double refDescend(const SelectionProblem& pb, const std::vector<RefItem>& items,
                  const SelectionObjective& objective, std::vector<std::uint8_t>& x) {
  const std::size_t channels = pb.channelCount();
  CoverState united(pb.universe());
  std::size_t chosen = 0;
  ChannelCounts counts{};
  for (std::size_t a = 0; a < x.size(); ++a) {
    if (!x[a]) continue;
    for (std::size_t k = 0; k < channels; ++k)
      counts[k] += united.gain(items[a].parts[k], items[a].words);
    united.add(items[a].set, items[a].words);
    ++chosen;
  }
  const auto flipped = [&](std::size_t a) {
    ChannelCounts c = counts;
    for (std::size_t k = 0; k < channels; ++k) {
      if (x[a]) {
        c[k] -= united.loss(items[a].parts[k], items[a].words);
      } else {
        c[k] += united.gain(items[a].parts[k], items[a].words);
      }
    }
    return c;
  };
  double e = objective.energy(chosen, counts);
  for (;;) {
    std::size_t bestFlip = x.size();
    double bestE = e - 1e-12;
    for (std::size_t a = 0; a < x.size(); ++a) {
      const double f = objective.energy(x[a] ? chosen - 1 : chosen + 1, flipped(a));
      if (f < bestE) bestE = f, bestFlip = a;
    }
    if (bestFlip == x.size()) return e;
    const std::size_t a = bestFlip;
    counts = flipped(a);
    if (x[a]) {
      united.remove(items[a].set, items[a].words);
      --chosen;
    } else {
      united.add(items[a].set, items[a].words);
      ++chosen;
    }
    x[a] ^= 1;
    e = objective.energy(chosen, counts);
  }
}

class RefBranchAndBound {
 public:
  RefBranchAndBound(const SelectionProblem& pb, const std::vector<RefItem>& items,
                    const SelectionObjective& objective, std::uint64_t budget)
      : pb_(pb), items_(items), objective_(objective), budget_(budget) {
    suffix_.assign(items.size() + 1, VoxelSet(pb.universe()));
    for (std::size_t t = items.size(); t-- > 0;) {
      suffix_[t] = suffix_[t + 1] | items[t].parts[pb.boundChannel()];
    }
  }
  bool run(std::vector<std::uint8_t>& best, double& bestEnergy) {
    best_ = best;
    bestEnergy_ = bestEnergy;
    std::vector<std::uint8_t> current(items_.size(), 0);
    search(0, 0, VoxelSet(pb_.universe()), current);
    best = best_;
    bestEnergy = bestEnergy_;
    return nodes_ <= budget_;
  }

 private:
  void search(std::size_t t, std::size_t chosen, const VoxelSet& united,
              std::vector<std::uint8_t>& current) {
    if (++nodes_ > budget_) return;
    const ChannelCounts counts = pb_.counts(united);
    const double e = objective_.energy(chosen, counts);
    if (e < bestEnergy_ - 1e-12) {
      bestEnergy_ = e;
      best_ = current;
    }
    if (t == items_.size()) return;
    const VoxelSet& bound = pb_.channel(pb_.boundChannel());
    const std::size_t reach = VoxelSet::countOr(united & bound, suffix_[t]);
    if (objective_.bound(chosen, counts, reach) >= bestEnergy_ - 1e-12) return;
    if (VoxelSet::countAndNot(items_[t].parts[pb_.boundChannel()], united) > 0) {
      current[t] = 1;
      search(t + 1, chosen + 1, united | items_[t].set, current);
      current[t] = 0;
    }
    search(t + 1, chosen, united, current);
  }

  const SelectionProblem& pb_;
  const std::vector<RefItem>& items_;
  const SelectionObjective& objective_;
  std::uint64_t budget_;
  std::uint64_t nodes_ = 0;
  std::vector<VoxelSet> suffix_;
  std::vector<std::uint8_t> best_;
  double bestEnergy_ = 0.0;
};

Selection refSolve(const SelectionProblem& pb, const SelectionObjective& objective,
                   const SelectionOptions& options) {
  const std::vector<RefItem> items = refItems(pb);
  Selection s;
  s.chosen.assign(items.size(), 0);
  s.energy = refDescend(pb, items, objective, s.chosen);
  std::mt19937_64 rng(options.seed);
  for (int restart = 0; restart < options.restarts; ++restart) {
    std::vector<std::uint8_t> x = s.chosen;
    for (std::size_t a = 0; a < x.size(); ++a) {
      if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) x[a] ^= 1;
    }
    const double e = refDescend(pb, items, objective, x);
    if (e < s.energy - 1e-12) {
      s.energy = e;
      s.chosen = x;
    }
  }
  RefBranchAndBound bb(pb, items, objective, options.nodeBudget);
  s.provedOptimal = bb.run(s.chosen, s.energy);
  return s;
}

// ---- Objectives: the two phases' energies, written out. ----

class TwoChannelObjective final : public SelectionObjective {
 public:
  TwoChannelObjective(std::size_t in, std::size_t out, double cost)
      : in_(in), out_(out), cost_(cost) {}
  double energy(std::size_t chosen, const ChannelCounts& removed) const override {
    return fit(chosen, removed[0], removed[1]);
  }
  double bound(std::size_t chosen, const ChannelCounts& removed, std::size_t reach) const override {
    return fit(chosen, removed[0], reach);
  }

 private:
  double fit(std::size_t chosen, std::size_t removedIn, std::size_t removedOut) const {
    const double den = double(in_ + out_ - removedOut);
    return double(chosen) * cost_ - 0.9 * (den > 0 ? double(in_ - removedIn) / den : 0.0);
  }
  std::size_t in_, out_;
  double cost_;
};

class CoverObjective final : public SelectionObjective {
 public:
  CoverObjective(std::size_t total, double cost) : total_(total), cost_(cost) {}
  double energy(std::size_t chosen, const ChannelCounts& c) const override {
    return double(chosen) * cost_ - 0.9 * double(c[0]) / double(total_);
  }
  double bound(std::size_t chosen, const ChannelCounts& c, std::size_t reach) const override {
    if (reach == c[0]) return std::numeric_limits<double>::infinity();
    return energy(chosen + 1, {reach, 0});
  }

 private:
  std::size_t total_;
  double cost_;
};

void expectSameSelection(const Selection& a, const Selection& b) {
  EXPECT_EQ(a.chosen, b.chosen);
  EXPECT_EQ(a.energy, b.energy);  // the same counts, so the same double
  EXPECT_EQ(a.provedOptimal, b.provedOptimal);
}

// Cached flip effects against CoverState, the bitset bookkeeping the
// previous descent recomputed them with, after each of `flips` random flips.
void expectEffectsMatchBitsets(const SelectionProblem& pb, const SelectionClasses& classes,
                               std::mt19937_64& rng, int flips) {
  const std::vector<RefItem> items = refItems(pb);
  const std::size_t n = items.size();
  ClassCover cover(classes);
  CoverState bits(pb.universe());
  std::vector<std::uint8_t> x(n, 0);
  for (int f = 0; f < flips && n > 0; ++f) {
    const std::size_t a = std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
    cover.flip(a);
    if (x[a]) {
      bits.remove(items[a].set);
    } else {
      bits.add(items[a].set);
    }
    x[a] ^= 1;
    ASSERT_EQ(cover.counts(), pb.counts(bits.covered())) << "flip " << f;
    for (std::size_t b = 0; b < n; ++b) {
      for (std::size_t k = 0; k < pb.channelCount(); ++k) {
        const std::size_t expected =
            x[b] ? bits.loss(items[b].parts[k]) : bits.gain(items[b].parts[k]);
        ASSERT_EQ(cover.flipEffect(b)[k], expected) << "flip " << f << ", item " << b;
      }
    }
  }
  // reset() from the last choice gives the same state.
  ClassCover fresh(classes);
  fresh.reset(x);
  EXPECT_EQ(fresh.counts(), cover.counts());
  for (std::size_t b = 0; b < n; ++b) EXPECT_EQ(fresh.flipEffect(b), cover.flipEffect(b));
}

TEST(SelectionClasses, CountsEveryUnionExactly) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t bits = 100 + 97 * std::size_t(trial);
    const VoxelSet good = randomSet(bits, rng, 6, bits / 5);
    SelectionProblem pb({good, good.complemented()}, 1);
    for (int i = 0; i < 3 + trial; ++i) pb.add(randomSet(bits, rng, 3, bits / 4), std::uint32_t(i));
    const SelectionClasses classes(pb);
    ASSERT_EQ(classes.itemCount(), pb.items().size());
    // Classes hold each voxel of an item once: an item's classes weigh its voxels.
    for (std::size_t a = 0; a < pb.items().size(); ++a) {
      ChannelCounts sum{};
      for (std::uint32_t c : classes.classesOf(a)) {
        for (std::size_t k = 0; k < 2; ++k) sum[k] += classes.weight(c)[k];
        const auto in = classes.itemsOf(c);
        EXPECT_TRUE(std::binary_search(in.begin(), in.end(), std::uint32_t(a)));
      }
      EXPECT_EQ(sum, pb.counts(pb.items()[a].set));
    }
    for (std::size_t c = 0; c < classes.size(); ++c) EXPECT_FALSE(classes.itemsOf(c).empty());
    expectEffectsMatchBitsets(pb, classes, rng, 40);
  }
}

TEST(SelectionClasses, GeneratedItemsGiveTheClassesOfTheBuiltSets) {
  std::mt19937_64 rng(6);
  for (int trial = 0; trial < 15; ++trial) {
    const std::size_t bits = 1000 + 301 * std::size_t(trial);
    const VoxelSet mask = randomSet(bits, rng, 8, bits / 6);
    const VoxelSet inside = randomSet(bits, rng, 5, bits / 4) & mask;
    const VoxelSet outside = mask - inside;
    std::vector<VoxelSet> gens;
    for (int i = 0; i < 4 + trial; ++i) gens.push_back(randomSet(bits, rng, 3, bits / 3));
    std::vector<const VoxelSet*> genRefs;
    for (const VoxelSet& g : gens) genRefs.push_back(&g);
    std::vector<GeneratedItem> items;
    SelectionProblem pb({inside.compress(mask), outside.compress(mask)}, 1);
    for (std::uint32_t i = 0; i < gens.size(); ++i) {
      for (bool complement : {false, true}) {
        if (std::uniform_int_distribution<int>(0, 2)(rng) == 0) continue;
        const VoxelSet local = gens[i].compress(mask);
        pb.add(complement ? local.complemented() : local, std::uint32_t(items.size()));
        items.push_back({i, complement});
      }
    }
    // Keep the generated list aligned with the problem's (duplicates dropped).
    std::vector<GeneratedItem> kept;
    for (const SelectionItem& it : pb.items()) kept.push_back(items[it.id]);
    const std::vector<const VoxelSet*> channels{&inside, &outside};
    const SelectionClasses fromGenerators(genRefs, kept, mask, channels);
    ASSERT_EQ(fromGenerators.itemCount(), pb.items().size());
    for (std::size_t a = 0; a < kept.size(); ++a) {
      ChannelCounts sum{};
      for (std::uint32_t c : fromGenerators.classesOf(a)) {
        for (std::size_t k = 0; k < 2; ++k) sum[k] += fromGenerators.weight(c)[k];
      }
      EXPECT_EQ(sum, pb.counts(pb.items()[a].set)) << "trial " << trial << ", item " << a;
    }
    expectEffectsMatchBitsets(pb, fromGenerators, rng, 30);
    // The same answers as the classes of the built sets, and as the reference.
    const TwoChannelObjective objective(inside.count(), outside.count(), 0.01);
    for (std::uint64_t budget : {20'000u, 40u, 3u}) {
      SelectionOptions o;
      o.nodeBudget = budget;
      o.seed = std::uint64_t(trial);
      const Selection ref = refSolve(pb, objective, o);
      expectSameSelection(solveSelection(pb, objective, o), ref);
      expectSameSelection(solveSelection(fromGenerators, 1, objective, o), ref);
    }
  }
}

TEST(SolveSelection, SameAnswersAsTheSolverOnEveryVoxel) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t bits = 300 + 41 * std::size_t(trial);
    const bool twoChannels = trial % 2 == 0;
    const VoxelSet good =
        twoChannels ? randomSet(bits, rng, 6, bits / 4) : VoxelSet(bits).complemented();
    std::vector<VoxelSet> channels{good};
    if (twoChannels) channels.push_back(good.complemented());
    SelectionProblem pb(channels, twoChannels ? 1 : 0);
    for (int i = 0; i < 4 + trial / 2; ++i)
      pb.add(randomSet(bits, rng, 3, bits / 5), std::uint32_t(i));
    for (std::uint64_t budget : {20'000u, 25u, 2u}) {
      SelectionOptions o;
      o.nodeBudget = budget;
      o.seed = std::uint64_t(trial) + 1;
      SCOPED_TRACE(testing::Message() << "trial " << trial << ", budget " << budget);
      if (twoChannels) {
        const TwoChannelObjective objective(good.count(), bits - good.count(), 0.02);
        expectSameSelection(solveSelection(pb, objective, o), refSolve(pb, objective, o));
      } else {
        const CoverObjective objective(bits, 0.01);
        expectSameSelection(solveSelection(pb, objective, o), refSolve(pb, objective, o));
      }
    }
  }
}

// ---- A real part: the phases' problems built from detected candidates. ----

struct RealPart {
  VoxelLabels labels;
  std::vector<DescriptionSet> d;
};

const RealPart& housingComplex() {
  static const RealPart part = [] {
    const CsgTree truth = readTreeJson(test::dataDir() / "housing_complex" / "tree.json");
    SampleOptions so;
    so.points = 30000;
    so.seed = 1;
    const PointCloud scan = sampleSurface(truth, so).cloud;
    DetectAndFitOptions fo;
    fo.resolution = 48;
    const SurfacesAndCandidates found = detectAndFit(scan, fo);
    RealPart p;
    p.labels = labelVoxels(found.grid, scan, LabelOptions{});
    std::vector<CsgTree> candidates;
    for (const Candidate& c : found.hypotheses.candidates) candidates.push_back(c.tree);
    p.d = describeAll(candidates, found.grid, p.labels);
    return p;
  }();
  return part;
}

// The previous selectSubtree: the root's own voxels built, then solved on
// every voxel.
SubtreeResult refSelectSubtree(const VoxelSet& root, const VoxelSet& inside,
                               const std::vector<const VoxelSet*>& neighbours,
                               const std::vector<std::uint32_t>& ids,
                               const SubtreeOptions& options) {
  SubtreeResult result;
  result.actionCount = 2 * neighbours.size();
  VoxelSet localInside = inside.compress(root);
  VoxelSet localOutside = localInside.complemented();
  const std::size_t insideCount = localInside.count();
  const std::size_t outsideCount = localInside.size() - insideCount;
  const double invL = options.minFeatureVoxels / double(std::max<std::size_t>(1, insideCount));
  SelectionProblem pb({std::move(localInside), std::move(localOutside)}, 1);
  std::vector<double> score;
  for (std::size_t i = 0; i < neighbours.size() && outsideCount > 0; ++i) {
    const VoxelSet local = neighbours[i]->compress(root);
    for (int sub = 0; sub < 2; ++sub) {
      VoxelSet removes = sub ? local : local.complemented();
      const std::size_t removesOut = VoxelSet::countAnd(removes, pb.channel(1));
      if (removesOut == 0) continue;
      if (options.alpha * double(removesOut) <= options.minFeatureVoxels) continue;
      const double out = double(removesOut), removedCount = double(removes.count());
      if (pb.add(std::move(removes), std::uint32_t(2 * i + std::size_t(sub)))) {
        score.push_back(out / (1.0 + removedCount - out));
      }
    }
  }
  result.usefulActions = pb.items().size();
  pb.sortByDescending(score);
  // TruncationObjective of subtree_selection.cpp.
  class Objective final : public SelectionObjective {
   public:
    Objective(std::size_t in, std::size_t out, double invL, double alpha)
        : in_(in), out_(out), invL_(invL), alpha_(alpha) {}
    double energy(std::size_t chosen, const ChannelCounts& r) const override {
      return fit(chosen, r[0], r[1]);
    }
    double bound(std::size_t chosen, const ChannelCounts& r, std::size_t reach) const override {
      return fit(chosen, r[0], reach);
    }

   private:
    double fit(std::size_t chosen, std::size_t removedIn, std::size_t removedOut) const {
      const double num = double(in_ - removedIn);
      const double den = double(in_ + out_ - removedOut);
      return double(chosen) * invL_ - alpha_ * (den > 0.0 ? num / den : 0.0);
    }
    std::size_t in_, out_;
    double invL_, alpha_;
  };
  const Selection best = refSolve(pb, Objective(insideCount, outsideCount, invL, options.alpha),
                                  {3, streamSeed(options.seed, 12345), options.nodeBudget, {}});
  result.provedOptimal = best.provedOptimal;
  result.energy = best.energy;
  result.voxels = root;
  for (std::size_t a = 0; a < best.chosen.size(); ++a) {
    if (!best.chosen[a]) continue;
    const std::size_t idx = pb.items()[a].id;
    result.actions.push_back({ids[idx / 2], idx % 2 == 1});
    if (idx % 2 == 1) {
      result.voxels.subtract(*neighbours[idx / 2]);
    } else {
      result.voxels &= *neighbours[idx / 2];
    }
  }
  return result;
}

TEST(SelectionClasses, PhaseOneOnARealPartMatchesThePreviousSolver) {
  const RealPart& part = housingComplex();
  const auto& d = part.d;
  ASSERT_GT(d.size(), 20u);
  std::size_t roots = 0, withActions = 0;
  for (std::uint32_t j = 0; j < d.size(); ++j) {
    if (d[j].plus == 0 || d[j].exceedsGrid || d[j].minus == 0) continue;
    std::vector<const VoxelSet*> nb;
    std::vector<std::uint32_t> ids;
    for (std::uint32_t k = 0; k < d.size(); ++k) {
      if (k != j && VoxelSet::intersects(d[k].voxels, d[j].voxels)) {
        nb.push_back(&d[k].voxels);
        ids.push_back(k);
      }
    }
    for (std::uint64_t budget : {20'000u, 30u}) {
      SubtreeOptions o;
      o.nodeBudget = budget;
      SCOPED_TRACE(testing::Message() << "root " << j << ", budget " << budget);
      const SubtreeResult got = selectSubtree(d[j].voxels, part.labels.inside, nb, ids, o);
      const SubtreeResult ref = refSelectSubtree(d[j].voxels, part.labels.inside, nb, ids, o);
      EXPECT_EQ(got.actions, ref.actions);
      EXPECT_EQ(got.energy, ref.energy);
      EXPECT_EQ(got.voxels, ref.voxels);
      EXPECT_EQ(got.usefulActions, ref.usefulActions);
      EXPECT_EQ(got.provedOptimal, ref.provedOptimal);
      withActions += budget == 20'000u && !got.actions.empty();
    }
    ++roots;
  }
  EXPECT_GT(roots, 10u);
  EXPECT_GT(withActions, 3u);
}

TEST(SelectionClasses, PhaseTwoOnARealPartMatchesThePreviousSolver) {
  const RealPart& part = housingComplex();
  const VoxelSet& inside = part.labels.inside;
  std::vector<const VoxelSet*> sets;
  for (const DescriptionSet& s : part.d) {
    if (s.plus > 0 && !s.exceedsGrid) sets.push_back(&s.voxels);
  }
  // The previous selectUnion's problem, built on the inside voxels.
  const std::size_t total = inside.count();
  SelectionProblem pb({VoxelSet(total).complemented()}, 0);
  std::vector<double> sizes;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    VoxelSet c = sets[i]->compress(inside);
    const std::size_t size = c.count();
    if (size > 0 && pb.add(std::move(c), std::uint32_t(i))) sizes.push_back(double(size));
  }
  pb.sortByDescending(sizes);
  std::mt19937_64 rng(8);
  expectEffectsMatchBitsets(pb, SelectionClasses(pb), rng, 25);
  for (std::uint64_t budget : {50'000u, 40u}) {
    UnionOptions o;
    o.nodeBudget = budget;
    const UnionResult got = selectUnion(inside, sets, o);
    // Eq. 6 as selectUnion weighs it.
    class Objective final : public SelectionObjective {
     public:
      Objective(double invM, double invTotal) : invM_(invM), invTotal_(invTotal) {}
      double energy(std::size_t chosen, const ChannelCounts& c) const override {
        return double(chosen) * invM_ - 0.9 * double(c[0]) * invTotal_;
      }
      double bound(std::size_t chosen, const ChannelCounts& c, std::size_t reach) const override {
        if (reach == c[0]) return std::numeric_limits<double>::infinity();
        return double(chosen + 1) * invM_ - 0.9 * double(reach) * invTotal_;
      }

     private:
      double invM_, invTotal_;
    };
    const Selection ref = refSolve(pb, Objective(8.0 / double(total), 1.0 / double(total)),
                                   {8, streamSeed(1, 54321), budget, {}});
    std::vector<std::uint32_t> chosen;
    for (std::size_t i = 0; i < ref.chosen.size(); ++i) {
      if (ref.chosen[i]) chosen.push_back(pb.items()[i].id);
    }
    std::sort(chosen.begin(), chosen.end());
    SCOPED_TRACE(testing::Message() << "budget " << budget);
    EXPECT_EQ(got.chosen, chosen);
    EXPECT_EQ(got.energy, ref.energy);
    EXPECT_EQ(got.provedOptimal, ref.provedOptimal);
    EXPECT_FALSE(got.chosen.empty());
  }
}

// One phase-1 problem of the real part, for the cached effects.
TEST(ClassCover, CachedEffectsOnARealPartMatchRecomputation) {
  const RealPart& part = housingComplex();
  const auto& d = part.d;
  // The root with the most neighbours among those to truncate.
  std::size_t best = d.size(), most = 0;
  for (std::size_t j = 0; j < d.size(); ++j) {
    if (d[j].plus == 0 || d[j].exceedsGrid || d[j].minus == 0) continue;
    std::size_t nb = 0;
    for (std::size_t k = 0; k < d.size(); ++k) {
      nb += k != j && VoxelSet::intersects(d[k].voxels, d[j].voxels);
    }
    if (nb > most) most = nb, best = j;
  }
  ASSERT_LT(best, d.size());
  const VoxelSet& root = d[best].voxels;
  const VoxelSet localInside = part.labels.inside.compress(root);
  SelectionProblem pb({localInside, localInside.complemented()}, 1);
  std::vector<const VoxelSet*> gens;
  std::vector<GeneratedItem> items;
  for (std::size_t k = 0; k < d.size(); ++k) {
    if (k == best || !VoxelSet::intersects(d[k].voxels, root)) continue;
    const VoxelSet local = d[k].voxels.compress(root);
    for (bool complement : {true, false}) {
      if (pb.add(complement ? local.complemented() : local, std::uint32_t(items.size()))) {
        items.push_back({std::uint32_t(gens.size()), complement});
      }
    }
    gens.push_back(&d[k].voxels);
  }
  const VoxelSet rootInside = root & part.labels.inside, rootOutside = root - part.labels.inside;
  const std::vector<const VoxelSet*> channels{&rootInside, &rootOutside};
  const SelectionClasses classes(gens, items, root, channels);
  EXPECT_GT(items.size(), 20u);
  EXPECT_GT(classes.size(), 20u);
  EXPECT_LT(classes.size(), root.count());
  std::mt19937_64 rng(9);
  expectEffectsMatchBitsets(pb, classes, rng, 60);
}

}  // namespace
}  // namespace csgvox
