#include "evolve/genetic_search.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include "evolve/redundancy.h"

namespace csgvox {
namespace {

using Clock = std::chrono::steady_clock;

struct Creature {
  CsgTree tree;
  double fitness = 0.0;
};

// Fitness of every tree of a generation: trees already known (same structure
// as a creature of the previous generation) are looked up, the others are
// evaluated together, each once.
class Evaluator {
 public:
  explicit Evaluator(const FitnessModel* model) : model_(model) {}

  void setModel(const FitnessModel* model) {
    model_ = model;
    known_.clear();
  }

  void evaluate(std::vector<Creature>& creatures, std::size_t& evaluations) {
    std::vector<std::size_t> hashes(creatures.size());
    std::vector<std::size_t> todo;  // indices of the first occurrence of each unknown tree
    std::vector<std::ptrdiff_t> sameAs(creatures.size(), -1);
    for (std::size_t i = 0; i < creatures.size(); ++i) {
      hashes[i] = creatures[i].tree.structuralHash();
      if (const double* f = find(creatures[i].tree, hashes[i])) {
        creatures[i].fitness = *f;
        continue;
      }
      for (const std::size_t j : todo) {
        if (hashes[j] == hashes[i] && creatures[j].tree.structurallyEqual(creatures[i].tree)) {
          sameAs[i] = std::ptrdiff_t(j);
          break;
        }
      }
      if (sameAs[i] < 0) todo.push_back(i);
    }
    std::vector<const CsgTree*> trees;
    trees.reserve(todo.size());
    for (const std::size_t i : todo) trees.push_back(&creatures[i].tree);
    const std::vector<Fitness> fitness = model_->evaluate(trees);
    for (std::size_t k = 0; k < todo.size(); ++k) creatures[todo[k]].fitness = fitness[k].total;
    evaluations += todo.size();
    for (std::size_t i = 0; i < creatures.size(); ++i) {
      if (sameAs[i] >= 0) creatures[i].fitness = creatures[std::size_t(sameAs[i])].fitness;
    }
    // What this generation knows is what the next one can look up.
    known_.clear();
    for (std::size_t i = 0; i < creatures.size(); ++i) {
      known_[hashes[i]].push_back({creatures[i].tree, creatures[i].fitness});
    }
  }

 private:
  const double* find(const CsgTree& tree, std::size_t hash) const {
    const auto it = known_.find(hash);
    if (it == known_.end()) return nullptr;
    for (const auto& [t, f] : it->second) {
      if (t.root() == tree.root() || t.structurallyEqual(tree)) return &f;
    }
    return nullptr;
  }

  const FitnessModel* model_;
  std::unordered_map<std::size_t, std::vector<std::pair<CsgTree, double>>> known_;
};

// Indices of the creatures by decreasing fitness (ties: lower index first).
std::vector<std::size_t> ranking(const std::vector<Creature>& creatures) {
  std::vector<std::size_t> order(creatures.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return creatures[a].fitness > creatures[b].fitness;
  });
  return order;
}

const Creature& tournament(EvolveRng& rng, const std::vector<Creature>& creatures,
                           std::size_t size) {
  const Creature* best = &creatures[uniformIndex(rng, creatures.size())];
  for (std::size_t k = 1; k < size; ++k) {
    const Creature& c = creatures[uniformIndex(rng, creatures.size())];
    if (c.fitness > best->fitness) best = &c;
  }
  return *best;
}

}  // namespace

std::string_view evolveStopName(EvolveStop stop) {
  switch (stop) {
    case EvolveStop::Generations:
      return "generations";
    case EvolveStop::Stalled:
      return "stalled";
    case EvolveStop::TimeLimit:
      return "time_limit";
    case EvolveStop::Cancelled:
      return "cancelled";
  }
  return "unknown";
}

EvolveResult evolve(const FitnessModel& model, std::span<const CsgTree> seeds,
                    const EvolveOptions& options, const GenerationCallback& onGeneration,
                    const FitnessModel* rough) {
  const PrimitiveLibrary& library = model.library();
  if (library.empty()) throw std::invalid_argument("evolve: no primitives to combine");
  if (options.population < options.elites + 1 || options.tournament == 0) {
    throw std::invalid_argument("evolve: the population must exceed the elites");
  }
  const Clock::time_point start = Clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  EvolveRng rng(options.seed);
  EvolveResult result;

  std::vector<Creature> population;
  population.reserve(options.population);
  for (const CsgTree& seed : seeds) {
    if (population.size() == options.population) break;
    if (!seed.empty()) population.push_back({library.adopt(seed), 0.0});
  }
  while (population.size() < options.population) {
    population.push_back({randomTree(rng, library, options.variation.initialDepth,
                                     options.variation.operationProbability),
                          0.0});
  }

  if (options.control.cancelled()) {
    result.stop = EvolveStop::Cancelled;
    return result;
  }
  bool roughPhase = rough != nullptr;
  Evaluator evaluator(roughPhase ? rough : &model);
  evaluator.evaluate(population, result.evaluations);
  // The population's ranking, kept in step with every evaluation.
  std::vector<std::size_t> order = ranking(population);
  double best = population[order.front()].fitness;
  std::size_t stall = 0;
  result.stop = EvolveStop::Generations;

  std::vector<Creature> next;
  next.reserve(options.population);
  for (std::size_t generation = 1; generation <= options.maxGenerations; ++generation) {
    if (options.control.cancelled()) {
      result.stop = EvolveStop::Cancelled;
      break;
    }
    if (options.control.pastDeadline()) {
      result.stop = EvolveStop::TimeLimit;
      break;
    }
    next.clear();
    for (std::size_t e = 0; e < options.elites; ++e) next.push_back(population[order[e]]);
    while (next.size() < options.population) {
      const double r = uniformUnit(rng);
      if (r < options.crossoverRate) {
        const Creature& a = tournament(rng, population, options.tournament);
        const Creature& b = tournament(rng, population, options.tournament);
        auto [c1, c2] = crossover(rng, a.tree, b.tree, options.variation);
        next.push_back({std::move(c1), 0.0});
        if (next.size() < options.population) next.push_back({std::move(c2), 0.0});
      } else if (r < options.crossoverRate + options.mutationRate) {
        const Creature& a = tournament(rng, population, options.tournament);
        next.push_back({mutate(rng, a.tree, library, options.variation), 0.0});
      } else {
        next.push_back(tournament(rng, population, options.tournament));
      }
    }
    if (options.normalizeOffspring) {
      for (std::size_t k = options.elites; k < next.size(); ++k)
        next[k].tree = normalizeTree(next[k].tree);
    }
    population.swap(next);
    evaluator.evaluate(population, result.evaluations);
    order = ranking(population);
    result.generations = generation;
    const Creature& leader = population[order.front()];
    if (leader.fitness > best) {
      best = leader.fitness;
      stall = 0;
    } else {
      ++stall;
    }
    if (onGeneration) {
      GenerationReport report{generation, best, leader.tree.nodeCount(), elapsed(), roughPhase};
      if (!onGeneration(report)) {
        result.stop = EvolveStop::Cancelled;
        break;
      }
    }
    if (options.stallGenerations > 0 && stall >= options.stallGenerations) {
      if (!roughPhase) {
        result.stop = EvolveStop::Stalled;
        break;
      }
      // The rough points have told what they can: go on with all of them.
      roughPhase = false;
      evaluator.setModel(&model);
      evaluator.evaluate(population, result.evaluations);
      order = ranking(population);
      best = population[order.front()].fitness;
      stall = 0;
    }
  }
  // A cancelled search's tree is not used: no more work on all points.
  const bool cancelled = result.stop == EvolveStop::Cancelled;
  if (roughPhase && !cancelled) {
    evaluator.setModel(&model);
    evaluator.evaluate(population, result.evaluations);
    order = ranking(population);
  }
  const Creature& winner = population[order.front()];
  result.best = cancelled ? winner.tree : removeRedundancy(winner.tree, model);
  if (!cancelled) result.fitness = model.evaluate(result.best);
  result.seconds = elapsed();
  return result;
}

}  // namespace csgvox
