// Speed of the genetic stage: fitness evaluations per second (points × tree
// nodes per second) with min/max, SARDF and R-functions on 10k and 100k
// points, and the time of one generation at population 150 on a 20k-point
// scan of a box with each of them.
//
//   bench_evolve [--quick]

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "core/cpu_features.h"
#include "evolve/fitness.h"
#include "evolve/genetic_search.h"
#include "evolve/tree_variation.h"
#include "tests/evolve_fixtures.h"

using namespace csgvox;

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// n points on the faces of [-1, 1]³ with outward normals, jittered.
void boxScan(std::size_t n, std::vector<Vec3>& points, std::vector<Vec3>& normals) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0), noise(-0.002, 0.002);
  points.clear();
  normals.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const int face = int(i % 6), axis = face / 2;
    Vec3 p(u(rng), u(rng), u(rng)), nrm = Vec3::Zero();
    p[axis] = face % 2 ? 1.0 : -1.0;
    nrm[axis] = p[axis];
    points.push_back(p + Vec3(noise(rng), noise(rng), noise(rng)));
    normals.push_back(nrm);
  }
}

// The box's six planes and distractors: 10 primitives in all, or `size`
// with seeded random spheres, cylinders and planes added (the libraries of
// the hybrid's regions hold 20 to 60).
PrimitiveLibrary boxLibrary(std::size_t size = 10) {
  std::vector<Primitive> extra{Sphere{Vec3(1, 1, 1), 0.5},
                               Cylinder{Vec3::Zero(), Vec3::UnitZ(), 0.3, 4.0},
                               HalfSpace{Vec3(1, 1, 0).normalized(), 1.2}, Sphere{Vec3::Zero(), 1.5}};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), r(0.1, 0.8);
  while (extra.size() + 6 < size) {
    const Vec3 c(u(rng), u(rng), u(rng));
    const Vec3 d = Vec3(u(rng), u(rng), u(rng)).normalized();
    switch (extra.size() % 3) {
      case 0:
        extra.push_back(Sphere{c, r(rng)});
        break;
      case 1:
        extra.push_back(Cylinder{c, d, r(rng), 4.0});
        break;
      default:
        extra.push_back(HalfSpace{d, u(rng)});
        break;
    }
  }
  return test::cubePlanes(std::move(extra));
}

// On one thread: the kernels' own speed.
void fitnessRate(std::size_t n, std::size_t primitives, SetOperationKind ops, const char* name,
                 bool quick) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<Vec3> points, normals;
  boxScan(n, points, normals);
  const PrimitiveLibrary library = boxLibrary(primitives);
  FitnessOptions fo;
  fo.operations = ops;
  const FitnessModel model(points, normals, 2.0 * std::sqrt(3.0), library, fo);
  EvolveRng rng(3);
  std::vector<CsgTree> trees;
  std::size_t nodes = 0;
  for (int i = 0; i < 150; ++i) {
    trees.push_back(randomTree(rng, library, 5, 0.8));
    nodes += trees.back().nodeCount();
  }
  std::vector<const CsgTree*> all;
  for (const CsgTree& t : trees) all.push_back(&t);
  const int rounds = quick ? 1 : (n > 50000 ? 3 : 20);
  double sink = 0.0;
  Clock::time_point t0 = Clock::now();
  for (int r = 0; r < rounds; ++r) {
    for (const CsgTree& t : trees) sink += model.evaluate(t).total;
  }
  const double one = seconds(t0) / rounds;
  t0 = Clock::now();
  for (int r = 0; r < rounds; ++r) {
    for (const Fitness& f : model.evaluate(all)) sink += f.total;
  }
  const double together = seconds(t0) / rounds;
  std::printf("| %s | %zu | %zu | %.1f | %.1f | %.3g | %.1f | %.3g |\n", name, n, primitives,
              double(nodes) / 150.0, 1e6 * one / 150.0, double(n) * double(nodes) / one,
              1e6 * together / 150.0, double(n) * double(nodes) / together);
  if (sink == 0.123) std::printf(" ");
}

void generationTime(std::size_t n, std::size_t primitives, SetOperationKind ops, const char* name,
                    int threads, bool quick) {
  std::vector<Vec3> points, normals;
  boxScan(n, points, normals);
  const PrimitiveLibrary library = boxLibrary(primitives);
  FitnessOptions fo;
  fo.operations = ops;
  const FitnessModel model(points, normals, 2.0 * std::sqrt(3.0), library, fo);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  EvolveOptions eo;
  // R-functions take tens of times longer: fewer generations of them.
  eo.maxGenerations = quick ? 20 : (ops == SetOperationKind::RFunction ? 40 : 200);
  eo.stallGenerations = 0;
  const Clock::time_point wall = Clock::now();
  const std::clock_t cpu = std::clock();
  const EvolveResult r = evolve(model, {}, eo);
  const double w = seconds(wall), c = double(std::clock() - cpu) / CLOCKS_PER_SEC;
  std::printf("| %s | %zu | %zu | %d | %zu | %.2f | %.2f | %.0f | %zu |\n", name, n, primitives,
              threads, r.generations,
              1e3 * w / double(r.generations), 1e3 * c / double(r.generations),
              double(r.evaluations) / double(r.generations), r.best.nodeCount());
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  std::printf("instruction set: %s (CSGVOX_SIMD=portable|avx2|avx512 chooses)\n\n",
              std::string(simdLevelName(simdLevel())).c_str());
  std::printf("Fitness of 150 random trees (depth <= 5), one thread\n\n");
  std::printf(
      "| operations | points | primitives | mean nodes | us per tree, one by one | points x nodes "
      "per s | us per tree, 150 together | points x nodes per s |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  for (const std::size_t n : {std::size_t(10000), std::size_t(100000)}) {
    fitnessRate(n, 10, SetOperationKind::MinMax, "min/max", quick);
    fitnessRate(n, 50, SetOperationKind::MinMax, "min/max", quick);
    fitnessRate(n, 10, SetOperationKind::Sardf, "SARDF", quick);
    fitnessRate(n, 50, SetOperationKind::Sardf, "SARDF", quick);
    fitnessRate(n, 10, SetOperationKind::RFunction, "R-function", quick);
  }
  std::printf("\nOne generation, population 150 (includes variation, caching, ranking)\n\n");
  std::printf(
      "| operations | points | primitives | threads | generations | wall ms per generation | CPU ms "
      "per generation | trees evaluated per generation | best tree nodes |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  const struct {
    SetOperationKind ops;
    const char* name;
  } kinds[] = {{SetOperationKind::MinMax, "min/max"},
               {SetOperationKind::Sardf, "SARDF"},
               {SetOperationKind::RFunction, "R-function"}};
  for (const std::size_t primitives : {std::size_t(10), std::size_t(50)}) {
    for (const auto& kind : kinds) {
      for (const int threads : {1, 2}) {
        generationTime(20000, primitives, kind.ops, kind.name, threads, quick);
      }
    }
  }
  return 0;
}
