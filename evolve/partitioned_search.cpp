#include "evolve/partitioned_search.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "core/seed.h"
#include "evolve/redundancy.h"

namespace csgvox {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Friedrich's bound on the height of a partition's trees: sqrt(π·C(n,2)).
std::size_t heightBound(std::size_t primitives, std::size_t cap) {
  const double pairs = 0.5 * double(primitives) * double(primitives > 0 ? primitives - 1 : 0);
  const auto bound = std::size_t(std::ceil(std::sqrt(M_PI * pairs)));
  return std::clamp<std::size_t>(bound, 2, std::max<std::size_t>(cap, 2));
}

// The fitness over a subset of the points, and its rough version.
struct PointModels {
  FitnessModel full;
  std::optional<FitnessModel> rough;
};

PointModels pointModels(std::span<const Vec3> points, std::span<const Vec3> normals,
                        std::span<const std::uint32_t> subset, double diagonal,
                        const PrimitiveLibrary& library, const FitnessOptions& fitness,
                        std::size_t roughPoints, std::uint64_t seed, const VoxelTarget* target) {
  std::vector<Vec3> p, n;
  p.reserve(subset.size());
  n.reserve(subset.size());
  for (const std::uint32_t i : subset) p.push_back(points[i]), n.push_back(normals[i]);
  FitnessModel full(p, n, diagonal, library, fitness, target);
  std::optional<FitnessModel> rough = roughModel(full, p, n, roughPoints, seed);
  return {std::move(full), std::move(rough)};
}

}  // namespace

PartitionedResult evolvePartitioned(std::span<const Vec3> points, std::span<const Vec3> normals,
                                    double diagonal, const PrimitiveLibrary& library,
                                    const FitnessOptions& fitness,
                                    const EvolveOptions& evolveOptions,
                                    const PartitionOptions& options,
                                    const GenerationCallback& onGeneration,
                                    const VoxelTarget* target) {
  const Clock::time_point start = Clock::now();
  PartitionedResult out;
  const FitnessModel whole(points, normals, diagonal, library, fitness, target);
  const std::optional<FitnessModel> wholeRough =
      roughModel(whole, points, normals, options.roughPoints, evolveOptions.seed);

  const double tolerance = options.supportTolerance * fitness.distanceTolerance * diagonal;
  const std::vector<SearchPartition> partitions = partitionSearch(
      primitiveSupport(points, library, tolerance), options.overlapMargin * diagonal);
  out.partitionSeconds = secondsSince(start);

  // One search per partition, all in parallel; each is deterministic for its
  // seed, so the set of results does not depend on the threads.
  const Clock::time_point searchStart = Clock::now();
  FitnessOptions partFitness = fitness;
  partFitness.voxelWeight = 0.0;
  // The partitions share half the time limit: each one starts with what is
  // left of it (they run a few at a time).
  const RunControl& control = evolveOptions.control;
  const RunControl partControl = control.deadline() == Clock::time_point::max()
                                     ? control
                                     : control.until(start + (control.deadline() - start) / 2);
  std::vector<CsgTree> trees(partitions.size());
  out.partitions.resize(partitions.size());
  tbb::parallel_for(std::size_t{0}, partitions.size(), [&](std::size_t k) {
    const SearchPartition& part = partitions[k];
    std::vector<Primitive> primitives;
    std::vector<std::string> names;
    for (const std::size_t p : part.primitives) {
      primitives.push_back(library.primitive(p));
      names.push_back(library.name(p));
    }
    const PrimitiveLibrary sub(std::move(primitives), std::move(names));
    EvolveOptions eo = evolveOptions;
    eo.control = partControl;
    eo.seed = mixSeed(evolveOptions.seed, k);
    eo.variation.maxDepth = heightBound(part.primitives.size(), evolveOptions.variation.maxDepth);
    eo.variation.initialDepth = std::min(eo.variation.initialDepth, eo.variation.maxDepth);
    eo.variation.mutationDepth = std::min(eo.variation.mutationDepth, eo.variation.maxDepth);
    const PointModels models = pointModels(points, normals, part.points, diagonal, sub, partFitness,
                                           options.roughPoints, eo.seed, nullptr);
    const Clock::time_point t = Clock::now();
    EvolveResult r = evolve(models.full, {}, eo, {}, models.rough ? &*models.rough : nullptr);
    if (!r.best.empty()) trees[k] = library.adopt(r.best);
    out.partitions[k] = {part.primitives, part.points.size(), r.generations, r.best.nodeCount(),
                         secondsSince(t)};
  });
  out.searchSeconds = secondsSince(searchStart);
  if (control.cancelled()) {  // no merge: the result is not used
    out.search.stop = EvolveStop::Cancelled;
    return out;
  }

  const Clock::time_point mergeStart = Clock::now();
  CsgTree merged;
  if (!trees.empty()) merged = normalizeTree(mergePartitionTrees(trees));
  out.mergedNodes = merged.nodeCount();
  out.mergeSeconds = secondsSince(mergeStart);

  const Clock::time_point finalStart = Clock::now();
  if (options.finalSearch || merged.empty()) {
    const EvolveOptions& eo = evolveOptions;
    std::vector<CsgTree> seeds;
    if (!merged.empty()) seeds.push_back(merged);
    seeds.insert(seeds.end(), trees.begin(), trees.end());
    out.search = evolve(whole, seeds, eo, onGeneration, wholeRough ? &*wholeRough : nullptr);
  } else {
    out.search.best = removeRedundancy(merged, whole);
    out.search.fitness = whole.evaluate(out.search.best);
  }
  out.finalSeconds = secondsSince(finalStart);
  out.search.seconds = secondsSince(start);
  return out;
}

}  // namespace csgvox
