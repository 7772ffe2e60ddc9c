// Tree evaluations per second on 100k points for each bundled tree
// (data/*/tree.json), single thread, on the same points: evaluate().f (the
// gradient path, through the set operations' virtual calls at every node),
// the per-point value() path and the batched values() path.
// Usage: bench_tree_eval [data dir]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "core/csg_tree.h"
#include "io/tree_json.h"

namespace {

using namespace csgvox;
namespace fs = std::filesystem;

constexpr std::size_t kPoints = 100000;
constexpr double kMinSeconds = 0.5;  // each path runs at least this long

// kPoints uniform points in the tree's bounds grown by 10 % on each side.
std::vector<Vec3> samplePoints(const CsgTree& tree) {
  const Aabb b = tree.bounds();
  const Vec3 lo = b.min - 0.1 * b.size(), hi = b.max + 0.1 * b.size();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points(kPoints);
  for (Vec3& p : points) {
    for (int k = 0; k < 3; ++k) p[k] = lo[k] + u(rng) * (hi[k] - lo[k]);
  }
  return points;
}

// Evaluations of the whole point set per second, and a checksum of the values.
template <class Fn>
double rate(Fn&& evaluateAll, double& checksum) {
  int runs = 0;
  const auto start = std::chrono::steady_clock::now();
  do {
    checksum = evaluateAll();
    ++runs;
  } while (bench::seconds(start) < kMinSeconds);
  return runs / bench::seconds(start);
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path data = argc > 1 ? fs::path(argv[1]) : fs::path(CSGVOX_DATA_DIR);
  std::vector<fs::path> trees;
  for (const auto& entry : fs::directory_iterator(data)) {
    if (fs::exists(entry.path() / "tree.json")) trees.push_back(entry.path() / "tree.json");
  }
  std::sort(trees.begin(), trees.end());
  std::printf("%-18s %6s %14s %14s %14s %9s\n", "tree", "leaves", "evaluate() /s", "value() /s",
              "values() /s", "speed-up");
  for (const fs::path& path : trees) {
    const CsgTree tree = readTreeJson(path);
    const std::vector<Vec3> points = samplePoints(tree);
    std::vector<double> out(points.size());
    double gradientSum = 0.0, perPointSum = 0.0, batchedSum = 0.0;
    const double gradient = rate(
        [&] {
          double s = 0.0;
          for (std::size_t i = 0; i < points.size(); ++i) s += tree.evaluate(points[i]).f;
          return s;
        },
        gradientSum);
    const double perPoint = rate(
        [&] {
          double s = 0.0;
          for (std::size_t i = 0; i < points.size(); ++i) s += out[i] = tree.value(points[i]);
          return s;
        },
        perPointSum);
    const double batched = rate(
        [&] {
          tree.values(points, out);
          double s = 0.0;
          for (double v : out) s += v;
          return s;
        },
        batchedSum);
    if (perPointSum != batchedSum || gradientSum != perPointSum) {
      std::fprintf(stderr, "%s: the paths disagree\n", path.string().c_str());
      return 1;
    }
    std::printf("%-18s %6zu %14.1f %14.1f %14.1f %8.1fx\n",
                path.parent_path().filename().string().c_str(), tree.primitiveCount(), gradient,
                perPoint, batched, batched / gradient);
  }
  std::printf("(evaluations of the tree at %zu points per second, one thread)\n", kPoints);
  return 0;
}
