// The whole reconstruction on synthetic scans of a bundled part at several
// sizes and grid resolutions: time per pipeline stage, the tree's size, and
// peak memory; then the two steps the CLI runs after the pipeline, meshing the
// tree at res 160 (mesh.ply, without writing it) and the fit metrics.
// Run: build/bench/bench_pipeline [data/<part>/tree.json] [noise] [--points N,N,...]
//        [--res R,R,...] [--threads T,T,...]
// Points default to 50k, 100k, 500k, 1M and 2M, resolutions to 64 and 128;
// --threads runs every row at each thread count (tbb::global_control; 0 or
// absent: all cores), so a stage's CPU and wall seconds at 1 and 2 threads
// give its serial fraction. Each stage is printed with its wall and CPU
// seconds (all threads).
//
// Or: build/bench/bench_pipeline --optimisation [data/<part>/tree.json]
//       [points] [repeats] [threads]
// times Wu's optimisations alone (constructCsg: the subtrees, the union and
// its refinement) at res 64 and 128 on one scan of the part, `repeats` times
// each (default 5; threads: all cores by default), after preparing the candidates' description sets
// once; prints every run and the median, and whether every run built the same tree.
//
// Peak memory: getrusage's maxrss only ever grows within a process, so each
// row runs in a child process of its own (fork) that starts small, before the
// parent has built anything large or started TBB's threads. A row's figures
// are therefore its own: peak RSS of sampling the scan plus the pipeline
// (pipe_MiB), and of all of it plus meshing and the fit metrics (peak_MiB).

#include <sys/resource.h>
#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_common.h"
#include "core/nearest_neighbors.h"
#include "io/tree_json.h"
#include "mesh/fit_metrics.h"
#include "mesh/mesh_export.h"
#include "mesh/surface_sampler.h"
#include "optimize/csg_construction.h"
#include "pipeline/detect_and_fit.h"
#include "pipeline/reconstruct.h"
#include "voxel/description_sets.h"

namespace {

using namespace csgvox;

using csgvox::bench::peakMiB;
using csgvox::bench::seconds;

// User + system CPU seconds of the whole process so far, all threads.
double cpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// Wall and CPU seconds of one stage of reconstruct(), or -1 when it did not run.
const StageTime* findStage(const Reconstruction& rec, const char* stage) {
  for (const StageTime& t : rec.timings) {
    if (t.stage == stage) return &t;
  }
  return nullptr;
}
double stageSeconds(const Reconstruction& rec, const char* stage) {
  const StageTime* t = findStage(rec, stage);
  return t ? t->seconds : -1.0;
}
double stageCpuSeconds(const Reconstruction& rec, const char* stage) {
  const StageTime* t = findStage(rec, stage);
  return t ? t->cpuSeconds : -1.0;
}

// The stages of a row, in order.
constexpr const char* kStages[] = {"detect",           "hypotheses",   "labels",
                                   "description_sets", "optimisation", "repair"};

// "1,2,4" as numbers.
std::vector<std::size_t> numberList(const std::string& text) {
  std::vector<std::size_t> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    out.push_back(std::size_t(std::stoull(text.substr(start, comma - start))));
    start = comma + 1;
  }
  return out;
}

// One row of the table: sample, reconstruct, mesh, fit. Returns the exit code.
int runRow(const CsgTree& part, std::size_t points, int resolution, double noise, int threads) {
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0) {
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  std::size_t(threads));
  }
  SampleOptions so;
  so.points = points;
  so.noise = noise;
  so.seed = 1;
  const PointCloud scan = sampleSurface(part, so).cloud;

  ReconstructOptions ro;
  ro.resolution = resolution;
  ro.seed = 1;
  const double cpu0 = cpuSeconds();
  const auto t0 = std::chrono::steady_clock::now();
  const Reconstruction rec = reconstruct(scan, ro);
  const double total = seconds(t0);
  const double cpu = cpuSeconds() - cpu0;
  const double pipelinePeak = peakMiB();

  double mesh = -1.0;
  double fit = -1.0;
  if (rec.ok()) {
    // As the CLI does: mesh.ply at its default --mesh-res, then the metrics.
    auto t = std::chrono::steady_clock::now();
    MeshOptions mo;
    mo.resolution = 160;
    const TriangleMesh triangles = meshTree(rec.tree, mo);
    mesh = seconds(t);
    t = std::chrono::steady_clock::now();
    FitOptions fo;
    fo.surfaceSamples = 100000;
    fo.seed = 1;
    const FitMetrics metrics = evaluateFit(rec.tree, scan, fo);
    fit = seconds(t);
    if (triangles.triangles.empty() || metrics.points != scan.size()) return 1;
  }
  std::printf("%8zu %4d %3d", points, resolution, threads);
  for (const char* stage : kStages) {
    std::printf(" %7.2f/%-7.2f", stageSeconds(rec, stage), stageCpuSeconds(rec, stage));
  }
  std::printf(" %7.2f/%-7.2f %6zu %9.0f | %9.3f %9.3f %9.3f %9.0f", total, cpu,
              rec.tree.primitiveCount(), pipelinePeak, mesh, fit,
              rec.ok() ? total + mesh + fit : -1.0, peakMiB());
  if (!rec.ok()) std::printf("  (%s)", rec.message.c_str());
  std::printf("\n");
  std::fflush(stdout);
  return rec.ok() ? 0 : 1;
}

// The --optimisation mode: constructCsg alone, as reconstruct() calls it.
int runOptimisation(const CsgTree& part, std::size_t points, int repeats) {
  SampleOptions so;
  so.points = points;
  so.seed = 1;
  const PointCloud scan = sampleSurface(part, so).cloud;
  std::printf(
      "optimisation (constructCsg) alone, %zu points; median wall-clock and CPU seconds (all "
      "threads)\n",
      points);
  std::printf("%4s %10s %6s %16s %9s %9s  %s\n", "res", "candidates", "prims", "tree_hash",
              "median_s", "cpu_s", "runs (wall)");
  for (int res : {64, 128}) {
    DetectAndFitOptions fo;
    fo.resolution = res;
    const SurfacesAndCandidates found = detectAndFit(scan, fo);
    if (!found.ok()) {
      std::printf("%4d detection failed\n", res);
      return 1;
    }
    LabelOptions lo;
    lo.noise = found.detection.noise;
    const VoxelLabels labels = labelVoxels(found.grid, scan, lo);
    std::vector<CsgTree> candidates;
    for (const Candidate& c : found.hypotheses.candidates) candidates.push_back(c.tree);
    const std::vector<DescriptionSet> d = describeAll(candidates, found.grid, labels);
    ConstructOptions co;
    co.snapDistance = found.grid.voxelSize();
    const NearestNeighbors index(scan.points);
    const double nearScan = std::max(0.5 * found.grid.voxelSize(), 3.0 * found.detection.noise);
    co.scannedAt = [&](const Vec3& p) {
      double d2 = 0.0;
      index.nearest(p, &d2);
      return d2 <= nearScan * nearScan;
    };
    std::vector<double> times, cpu;
    CsgTree first;
    bool same = true;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const double cpu0 = cpuSeconds();
      const Construction c = constructCsg(candidates, d, labels.inside, co);
      times.push_back(seconds(t0));
      cpu.push_back(cpuSeconds() - cpu0);
      if (r == 0) first = c.tree;
      same = same && c.tree == first;
    }
    const auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    std::printf("%4d %10zu %6zu %016zx %9.3f ", res, candidates.size(), first.primitiveCount(),
                first.structuralHash(), median(times));
    std::printf("%9.3f ", median(cpu));
    for (double t : times) std::printf(" %.3f", t);
    std::printf("%s\n", same ? "" : "  (trees differ between runs)");
    std::fflush(stdout);
    if (!same) return 1;
  }
  return 0;
}

int run(int argc, char** argv) {
  if (argc > 1 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf(
        "usage: %s [TREE.json] [NOISE] [--points N,...] [--res R,...] [--threads T,...]\n"
        "       %s --optimisation [TREE.json] [POINTS] [REPEATS] [THREADS]\n"
        "TREE.json: the part to sample (default data/housing_complex/tree.json); NOISE: "
        "Gaussian position noise, sigma as a fraction of D\n",
        argv[0], argv[0]);
    return 0;
  }
  if (argc > 1 && std::string(argv[1]) == "--optimisation") {
    const std::string path =
        argc > 2 ? argv[2] : std::string(CSGVOX_DATA_DIR) + "/housing_complex/tree.json";
    const std::size_t points = argc > 3 ? std::size_t(std::atoll(argv[3])) : 100000;
    const int repeats = argc > 4 ? std::max(1, std::atoi(argv[4])) : 5;
    const int threads = argc > 5 ? std::max(1, std::atoi(argv[5])) : 0;
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0) {
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(threads));
    }
    return runOptimisation(readTreeJson(std::filesystem::path(path)), points, repeats);
  }
  std::vector<std::string> positional;
  std::vector<std::size_t> pointCounts = {50000, 100000, 500000, 1000000, 2000000};
  std::vector<std::size_t> resolutions = {64, 128}, threadCounts = {0};
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    std::vector<std::size_t>* list = arg == "--points"    ? &pointCounts
                                     : arg == "--res"     ? &resolutions
                                     : arg == "--threads" ? &threadCounts
                                                          : nullptr;
    if (!list) {
      positional.push_back(arg);
      continue;
    }
    if (a + 1 >= argc) throw std::invalid_argument(arg + " needs a comma-separated list");
    *list = numberList(argv[++a]);
  }
  const std::string treePath = !positional.empty()
                                   ? positional[0]
                                   : std::string(CSGVOX_DATA_DIR) + "/housing_complex/tree.json";
  const double noise = positional.size() > 1 ? std::atof(positional[1].c_str()) : 0.0;
  const CsgTree part = readTreeJson(std::filesystem::path(treePath));
  std::printf("part %s, noise %.4f D, %zu primitives\n", treePath.c_str(), noise,
              part.primitiveCount());
  std::printf(
      "pipeline stages and total (reconstruct()): wall-clock / CPU seconds (all threads); "
      "thr: threads (0: all cores)\n");
  std::printf(
      "then what the CLI runs after it: meshTree at res 160, evaluateFit (100k samples); "
      "e2e = total + mesh + fit\n");
  std::printf(
      "peak memory per row, each row in a child process of its own "
      "(pipe: sampling + pipeline; peak: also mesh + fit); -1: not run\n");
  std::printf("%8s %4s %3s %15s %15s %15s %15s %15s %15s %15s %6s %9s | %9s %9s %9s %9s\n",
              "points", "res", "thr", "detect", "hypotheses", "labels", "dsets", "optimisation",
              "repair", "total", "prims", "pipe_MiB", "mesh160_s", "fit_s", "e2e_s", "peak_MiB");
  int failures = 0;
  for (const std::size_t n : pointCounts) {
    for (const std::size_t resolution : resolutions) {
      for (const std::size_t threads : threadCounts) {
      const int res = int(resolution);
      std::fflush(stdout);  // the child must not print the parent's buffer again
      const pid_t child = fork();
      if (child < 0) {
        std::perror("fork");
        return 1;
      }
      if (child == 0) {
        int code = 1;
        try {
          code = runRow(part, n, res, noise, int(threads));
        } catch (const std::exception& e) {
          std::printf("%8zu %4d failed: %s\n", n, res, e.what());
        }
        std::fflush(stdout);
        _exit(code);
      }
      int status = 0;
      if (waitpid(child, &status, 0) < 0) {
        std::perror("waitpid");
        return 1;
      }
      if (!WIFEXITED(status)) {
        std::printf("%8zu %4d killed by signal %d\n", n, res,
                    WIFSIGNALED(status) ? WTERMSIG(status) : 0);
      }
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) ++failures;
      }
    }
  }
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", argv[0], e.what());
    return 1;
  }
}
