#pragma once
/// The genetic search over CSG trees (Fayolle & Pasko 2016, §5.3, with
/// SURREAL's extra mutations): a population of trees over a primitive
/// library, each generation made of the best creatures (elitism) and of
/// offspring of tournament winners by subtree crossover, mutation or plain
/// copy; stops on a generation limit, a number of generations without
/// improvement, a time limit or cancellation, and returns the best tree
/// found, with its redundant nodes removed.
///
/// Creatures are evaluated in parallel (TBB); every random choice is drawn
/// in order from one generator seeded by options.seed, so a seed gives the
/// same tree whatever the number of threads.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

#include "core/csg_tree.h"
#include "core/run_control.h"
#include "evolve/fitness.h"
#include "evolve/tree_variation.h"

namespace csgvox {

/// Options of evolve().
struct EvolveOptions {
  std::size_t population = 150;        ///< creatures per generation
  std::size_t elites = 2;              ///< best creatures copied unchanged into the next generation
  std::size_t tournament = 2;          ///< creatures drawn per tournament
  double crossoverRate = 0.3;          ///< an offspring comes from crossover with this probability
  double mutationRate = 0.3;           ///< ... from mutation with this one (else a plain copy)
  std::size_t maxGenerations = 3000;   ///< generations at most
  std::size_t stallGenerations = 300;  ///< stop after this many without improvement (0: never)
  RunControl control;               ///< deadline (the best tree so far is kept) and cancel request
  std::uint64_t seed = 1;           ///< seeds every random choice
  VariationOptions variation;       ///< random trees, crossover depth bound, mutations
  bool normalizeOffspring = false;  ///< pass every offspring through normalizeTree (no X − X:
                                    ///< surfaces that bound no volume cannot explain points)
};

/// What one generation reached, for progress reports.
struct GenerationReport {
  std::size_t generation = 0;  ///< 1 for the first generation after the initial population
  double bestFitness = 0.0;    ///< best E(t) so far on the points in use
  std::size_t bestNodes = 0;   ///< size of that tree
  double seconds = 0.0;        ///< since the search started
  bool rough = false;          ///< the points in use are the rough model's
};

/// Called after every generation; returning false stops the search (the best
/// tree so far is returned).
using GenerationCallback = std::function<bool(const GenerationReport&)>;

/// Why the search stopped.
enum class EvolveStop { Generations, Stalled, TimeLimit, Cancelled };

/// Result of evolve().
struct EvolveResult {
  CsgTree best;                 ///< the best tree, redundancy removed
  Fitness fitness;              ///< its fitness on all points
  std::size_t generations = 0;  ///< generations run
  std::size_t evaluations = 0;  ///< trees whose fitness was computed (not found in the cache)
  double seconds = 0.0;         ///< wall time of the search
  EvolveStop stop = EvolveStop::Generations;
};

/// Runs the genetic search. The initial population holds `seeds` (their
/// leaves mapped to the library's, see PrimitiveLibrary::adopt) and random
/// trees. When `rough` is given (a model over a subset of the points), the
/// generations use it until the search stalls, then every creature is
/// re-ranked on `model` and the search goes on there; the final ranking
/// always uses `model`.
/// @throw std::invalid_argument when the library is empty, the population is
///        smaller than the elites plus one, or a seed has a leaf that is not
///        in the library.
EvolveResult evolve(const FitnessModel& model, std::span<const CsgTree> seeds,
                    const EvolveOptions& options = {}, const GenerationCallback& onGeneration = {},
                    const FitnessModel* rough = nullptr);

/// Lower-case name of a stop reason: "generations", "stalled", "time_limit", "cancelled".
std::string_view evolveStopName(EvolveStop stop);

}  // namespace csgvox
